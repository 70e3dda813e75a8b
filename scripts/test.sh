#!/usr/bin/env bash
# The README's test command (`make test` calls it): the whole suite but benchmarks and the long fuzz run, in
# two processes (pytest-xdist; up to four on a bigger machine), each drawing its windows on an Xvfb display
# of its own (tests/own_display.py). Xvfb and the Qt xcb libraries are installed from Debian first when they
# are missing and we are root (as on CI); without them the window's tests are skipped, saying so.
set -euo pipefail
PY=${1:-.venv/bin/python}
# one thread per process (conftest.py sets it for the test process): results that do not hang on the core
# count, and on a busy 2-core machine no OpenMP threads spinning against each other
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
# Python's byte-code cache on (an environment may switch it off): without it every process the tests start (the
# CLI's, Dask's workers, the FBX reader's) compiled this package anew, a quarter of the CLI tests' time
unset PYTHONDONTWRITEBYTECODE
APT_PACKAGES="xvfb xauth libxkbcommon-x11-0 libxcb-cursor0 libxcb-icccm4 libxcb-keysyms1 libxcb-shape0
  libxcb-randr0 libxcb-render-util0 libxcb-image0 libxcb-xinerama0 libxcb-xkb1 libegl1 libgl1 libfontconfig1
  libdbus-1-3"
if ! command -v Xvfb >/dev/null || ! /sbin/ldconfig -p | grep -q libxcb-cursor; then
  if [ "$(id -u)" = 0 ]; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $APT_PACKAGES >/dev/null
  else
    echo "no Xvfb: the window's tests will be skipped (sudo apt-get install $APT_PACKAGES)" >&2
  fi
fi
# a worker holds up to 3 GB (the real rigs' retargets): at most four, whatever the cores (nproc without the
# OMP_NUM_THREADS set above, which it would take for the answer)
CORES=$(env -u OMP_NUM_THREADS -u OMP_THREAD_LIMIT nproc)
WORKERS=$(( CORES < 2 ? 1 : (CORES > 4 ? 4 : CORES) ))
exec "$PY" -m pytest -q --durations=25 -n "$WORKERS" --dist worksteal -m "not benchmark and not fuzz_long"
