# motionlab: two commands do everything (`make course`, `make test`); `make bench` measures speed.
# Each target bootstraps .venv (editable install with pinned dependencies) when it is missing or
# when pyproject.toml changed since the last install. `make test` and `make course` keep their output in
# build/logs/<target>-<time>.log (the newest ten of each; motionlab/course/logs.py).
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.motionlab-installed

.PHONY: course test bench clean-build setup reference

setup: $(STAMP)

# The install goes through uv (from PyPI; resolves and installs the same pinned versions as pip in about a
# fifth of the time, bytecode compiled), with pip as the fallback where uv cannot be installed. torch comes
# from the local wheel directory pip is configured with (PIP_FIND_LINKS), when there is one. The package's own
# sources (an editable install, which neither compiles) are compiled too: where PYTHONDONTWRITEBYTECODE is set,
# every process would otherwise compile what it imports again (about 0.1 s of a notebook kernel's first
# cell, 0.4 s of a pytest worker's collection); a source edited later is compiled afresh as usual. For the
# same reason pytest's rewritten test modules (its assert messages) are written once here, by collecting the
# unit tests with bytecode writing on: each of `make test`'s three workers would otherwise rewrite all of them
# (2.4 s of CPU per worker); pytest rewrites a test module edited since, in memory, as it would anyway.
FIND_LINKS := $(firstword $(PIP_FIND_LINKS) $(wildcard /opt/wheels))

$(STAMP): pyproject.toml
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	( $(BIN)/python -m pip install --quiet uv && $(BIN)/uv pip install --quiet --python $(BIN)/python \
		--compile-bytecode $(if $(FIND_LINKS),--find-links $(FIND_LINKS)) -e . ) \
		|| $(BIN)/python -m pip install --quiet -e .
	$(BIN)/python -m compileall -q motionlab
	env -u PYTHONDONTWRITEBYTECODE $(BIN)/python -m pytest --collect-only -q -p no:cacheprovider tests >/dev/null \
		|| echo "setup: collecting the tests failed; make test will say why"
	@touch $@

# The full profile loads the shipped reference models (reference/); `make course RETRAIN=1` trains every model
# here instead (the build's checkpoint cache keeps them for the next build).
RETRAIN ?= 0

course: $(STAMP)
	MOTIONLAB_PROFILE=full MOTIONLAB_RETRAIN=$(RETRAIN) $(BIN)/python -m motionlab.course.logs course -- \
		$(BIN)/python -m motionlab.course

# Retrain the reference models: the course with every model trained afresh in build/reference-build, then
# the runs it used copied to reference/ with their manifests (even when a claim failed: the build's exit
# status is kept and returned). `make reference ALL=0` builds with the reference models in use instead: only
# the runs whose configuration changed are trained and replaced, the others are kept.
ALL ?= 1

reference: $(STAMP)
	rm -rf build/reference-build
	MOTIONLAB_BUILD=build/reference-build MOTIONLAB_PROFILE=full MOTIONLAB_RETRAIN=$(ALL) MOTIONLAB_REFERENCE_BUILD=1 \
		$(BIN)/python -m motionlab.course.logs reference -- $(BIN)/python -m motionlab.course; \
		status=$$?; $(BIN)/python -m motionlab.apps.reference export build/reference-build && exit $$status

# The formatter and the linter (ruff, settings in pyproject.toml) first, then the tests and notebooks; the
# log ends with the 25 slowest tests (--durations), so a test that grows slow shows itself. The notebooks train
# and measure in their own process (MOTIONLAB_PROCESSES=1) instead of starting worker processes of their own;
# three pytest workers keep both cores busy while one of them waits (for a kernel to start or to time out, a
# browser, a subprocess): 150.9 and 149.9 s of pytest against 158.4 and 151.9 s with two, runs alternating.
test: $(STAMP)
	MOTIONLAB_PROFILE=quick MOTIONLAB_PROCESSES=1 $(BIN)/python -m motionlab.course.logs test -- sh -c '\
		$(BIN)/ruff format --check . && $(BIN)/ruff check . && $(BIN)/lint-imports && \
		$(BIN)/python -m pytest -n 3 --dist loadscope --durations=25 \
			--nbval-sanitize-with tests/nbval_sanitize.cfg'

bench: $(STAMP)
	$(BIN)/python -m motionlab.bench

clean-build:
	rm -rf build
