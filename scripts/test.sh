#!/usr/bin/env bash
# The README's test command (`make test` calls it): the whole suite but benchmarks and the long fuzz
# run. The desktop
# window's tests need an X display; without one this starts Xvfb, installing it and the Qt xcb
# libraries from Debian first when they are missing and we are root (as on CI).
set -euo pipefail
PY=${1:-.venv/bin/python}
# one thread per process (conftest.py sets it for the test process): results that do not hang on the core
# count, and on a busy 2-core machine no OpenMP threads spinning against each other
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
APT_PACKAGES="xvfb xauth libxkbcommon-x11-0 libxcb-cursor0 libxcb-icccm4 libxcb-keysyms1 libxcb-shape0
  libxcb-randr0 libxcb-render-util0 libxcb-image0 libxcb-xinerama0 libxcb-xkb1 libegl1 libgl1 libfontconfig1
  libdbus-1-3"
if [ -z "${DISPLAY:-}" ]; then
  if ! command -v xvfb-run >/dev/null || ! /sbin/ldconfig -p | grep -q libxcb-cursor; then
    if [ "$(id -u)" = 0 ]; then
      apt-get update -qq
      DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $APT_PACKAGES >/dev/null
    else
      echo "no display and no Xvfb: the GUI tests will be skipped (sudo apt-get install $APT_PACKAGES)" >&2
    fi
  fi
  if command -v xvfb-run >/dev/null; then
    exec xvfb-run -a -s "-screen 0 1600x1000x24" "$PY" -m pytest -q --durations=25 -m "not benchmark and not fuzz_long"
  fi
fi
exec "$PY" -m pytest -q --durations=25 -m "not benchmark and not fuzz_long"
