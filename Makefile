# Hugger developer commands. `make demo` and `make test` set everything up on a fresh
# Debian machine (as root: system packages via apt-get), in a virtual environment .venv.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(CURDIR)/$(VENV)/bin
# chromium and chromium-driver: the headless browser the viewer test drives (tests/test_viewer.py);
# libqhull-dev: the compiled grasp quality (cpp/src/analysis)
APT_PACKAGES := libeigen3-dev libfcl-dev libgtest-dev libqhull-dev chromium chromium-driver
export PATH := $(BIN):$(PATH)

.PHONY: help deps venv install demo test test-cpp test-py test-sanitize fuzz bench clean

help:
	@echo "make demo           set up and run 'hugger demo': the paper's example, figures and animation in demo-out/"
	@echo "make test           set up and run the C++ (ctest) and Python (pytest) suites"
	@echo "make test-sanitize  C++ tests under AddressSanitizer + UndefinedBehaviorSanitizer"
	@echo "make bench          Release build of hugger_bench and the Python benchmarks"
	@echo "make fuzz           the long hypothesis fuzzing run (HUGGER_FUZZ_PROFILE=long)"
	@echo "make install        system packages, .venv, and the package with its test extras"

deps:
	@missing=""; for p in $(APT_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	command -v g++ >/dev/null 2>&1 || missing="$$missing g++"; \
	$(PYTHON) -m venv --help >/dev/null 2>&1 || missing="$$missing python3-venv python3-dev"; \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    echo "installing system packages:$$missing"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing >/dev/null; \
	  else \
	    echo "missing system packages:$$missing -- run: sudo apt-get install$$missing"; exit 1; \
	  fi; \
	fi

$(VENV)/bin/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip

venv: $(VENV)/bin/python

install: deps venv
	$(BIN)/python -m pip install -q "scikit-build-core>=0.10" "pybind11>=2.12" cmake ninja numpy
	$(BIN)/python -m pip install -q --no-build-isolation -Cbuild-dir=build/py -e ".[test]"

demo: install
	$(BIN)/hugger demo --out demo-out

test-cpp: install
	$(BIN)/cmake -S . -B build/ctest -G Ninja -DHUGGER_BUILD_TESTS=ON -DHUGGER_BUILD_PYTHON=OFF -DCMAKE_BUILD_TYPE=Release >/dev/null
	$(BIN)/cmake --build build/ctest -j 2
	cd build/ctest && $(BIN)/ctest --output-on-failure -j 2

test-py: install
	$(BIN)/python -m pytest -q

# Runs both suites; fails if either fails.
test: install
	@status=0; \
	$(MAKE) --no-print-directory test-cpp || status=1; \
	$(MAKE) --no-print-directory test-py || status=1; \
	exit $$status

test-sanitize: install
	$(BIN)/cmake -S . -B build/sanitize -G Ninja -DHUGGER_BUILD_TESTS=ON -DHUGGER_BUILD_PYTHON=OFF \
	  -DHUGGER_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
	$(BIN)/cmake --build build/sanitize -j 2
	cd build/sanitize && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 $(BIN)/ctest --output-on-failure -j 2

bench: install
	$(BIN)/cmake -S . -B build/bench -G Ninja -DHUGGER_BUILD_BENCH=ON -DHUGGER_BUILD_PYTHON=OFF -DCMAKE_BUILD_TYPE=Release >/dev/null
	$(BIN)/cmake --build build/bench -j 2
	build/bench/hugger_bench --repeat 3
	$(BIN)/python bench/bench_python.py --repeat 3

fuzz: install
	HUGGER_FUZZ_PROFILE=long $(BIN)/python -m pytest -q tests/properties/test_fuzz.py tests/test_hands.py::test_random_layouts_many

clean:
	rm -rf build $(VENV) demo-out
