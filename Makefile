# Two entry points for a fresh machine: `make run` and `make test` (see README).
PYTHON ?= python3
VENV   ?= .venv
PY      = $(VENV)/bin/python
STAMP   = $(VENV)/.installed
# Blender (bpy on PyPI: Python 3.11 only, numpy < 2) lives in a venv of its own, driven as a subprocess
BLENDER_PYTHON ?= python3.11
BLENDER_VENV   ?= .venv-blender
BLENDER_STAMP   = $(BLENDER_VENV)/.installed

.PHONY: run test bench assets train screenshots clean blender

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q torch==2.13.0
	$(PY) -m pip install -q -e ".[test]"
	touch $(STAMP)

run: $(STAMP)
	$(VENV)/bin/s2h view

# CI (CI=true) builds the Blender venv too, so that the Blender round trip (tests/test_blender_roundtrip.py) runs;
# the two venvs are built side by side (one pip each: 40 s of a fresh clone's 160 s setup saved on two cores)
test:
	$(MAKE) -j2 $(STAMP) $(if $(CI),$(BLENDER_STAMP))
	bash scripts/test.sh $(PY)

# the Blender round-trip check's venv (374 MB: bpy 5.0.1); `make test` runs that check once it is there
blender: $(BLENDER_STAMP)

$(BLENDER_STAMP):
	$(BLENDER_PYTHON) -m venv $(BLENDER_VENV)
	$(BLENDER_VENV)/bin/python -m pip install -q --upgrade pip
	$(BLENDER_VENV)/bin/python -m pip install -q bpy==5.0.1
	touch $(BLENDER_STAMP)

bench: $(STAMP)
	$(PY) benchmarks/bench_asm_fk.py
	$(PY) benchmarks/bench_retarget.py
	$(PY) benchmarks/bench_annotate.py
	$(PY) benchmarks/bench_real_rigs.py
	$(PY) benchmarks/bench_gltf_json.py
	$(PY) benchmarks/bench_playback.py
	$(PY) benchmarks/bench_batch.py
	$(PY) benchmarks/bench_tracking.py
	$(if $(DISPLAY),,xvfb-run -a -s "-screen 0 1600x1000x24") $(PY) benchmarks/bench_window_playback.py

# reproduces assets/models/{asrn,dm}.pt (seeded): both at once, one core each (small batches gain
# nothing from a second thread, and two threads spin badly on a busy machine); about 20 minutes here
train: $(STAMP)
	OMP_NUM_THREADS=1 $(VENV)/bin/s2h train --kind asrn --quiet & asrn=$$!; \
	OMP_NUM_THREADS=1 $(VENV)/bin/s2h train --kind dm; dm=$$?; wait $$asrn && exit $$dm

# docs/compare_mode.png and docs/annotation_mode.png from the real window (under Xvfb without a display)
screenshots: $(STAMP)
	$(if $(DISPLAY),,xvfb-run -a -s "-screen 0 1600x1000x24") $(PY) scripts/make_screenshots.py

assets: $(STAMP)
	$(PY) scripts/generate_assets.py

clean:
	rm -rf $(VENV) $(BLENDER_VENV) .pytest_cache
