# The two commands of the README's Quick start, and a few more for developers.
#   make run    install what the command needs (scripts/install-deps run), build the nhdyn command
#               (Release) and only it, simulate the default example (examples/sled.toml;
#               MODEL=... NAME=... for another)
#   make test   install everything else (test libraries, Python, Jupyter, Chromium...), build
#               everything (Release), run every test through ctest
#   make asan   the tests again under AddressSanitizer + UndefinedBehaviorSanitizer (build-asan/)
#   make fuzz   the model-file fuzzer (needs clang-14; fuzz/run says which packages)
#   make bench  build and run the benchmarks
#   make python install what make test needs (scripts/install-deps), configure as make test does, build
#               the Python package nhdyn only, and say how to import it
#   make bench-check   the performance guard: a few paired ratios against bench/baselines (fails
#               when one is more than 1.5x its baseline; about 40 s on 2 busy cores)
#   make bench-update  the same, and rewrites docs/performance.md's table (BASELINES=1: and
#               bench/baselines)
#   make package  the Debian package build/nhdyn_VERSION_ARCH.deb (CPack; docs/install.md)
#   make perf-figures  measure the figures of docs/performance.md and rewrite its table (several
#               minutes; QUICK=1: about one)
#   make docs   the documentation site in $(BUILD)/docs/html (docs/install.md): Sphinx, Doxygen
#   make docs-update  rewrite the quoted outputs of README.md and docs/ from real runs
BUILD ?= build
JOBS ?= $(shell nproc)
MODEL ?= examples/sled.toml
NAME ?= sled

.PHONY: run test build configure configure-run deps deps-run bench bench-check bench-update python package asan fuzz clean docs docs-update perf-figures

deps:
	@bash scripts/install-deps

deps-run:
	@bash scripts/install-deps run

CONFIGURE = cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release $(if $(CI),-DNHDYN_WERROR=ON)
# Everything on (the options are cached: a build configured by `make run` turns them back on).
configure: deps
	@$(CONFIGURE) -DNHDYN_BUILD_TESTS=ON -DNHDYN_BUILD_BENCH=ON -DNHDYN_BUILD_PYTHON=ON >/dev/null

# The CLI alone: no test, benchmark or Python package, so none of their packages is needed. The
# same build folder, so that `make test` afterwards reuses every object.
configure-run: deps-run
	@$(CONFIGURE) -DNHDYN_BUILD_TESTS=OFF -DNHDYN_BUILD_BENCH=OFF -DNHDYN_BUILD_PYTHON=OFF >/dev/null

# Everything: library, CLI, tests, examples, benchmarks.
build: configure
	@cmake --build $(BUILD) -j $(JOBS)

# The main job needs the CLI only (about half of the whole build).
run: configure-run
	@cmake --build $(BUILD) -j $(JOBS) --target nhdyn_command
	@mkdir -p results
	$(BUILD)/apps/nhdyn/nhdyn simulate $(MODEL) -o results/$(NAME).csv --plot results/$(NAME).png

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

python: configure
	@cmake --build $(BUILD) -j $(JOBS) --target nhdyn_python
	@echo "export PYTHONPATH=$(abspath $(BUILD))/python   # then: /usr/bin/python3 -c 'import nhdyn'"

# The documentation site (docs/install.md, "The documentation site"; docs/conf.py): the pages of
# docs/ (Sphinx with MyST), the C++ API from the headers (Doxygen, Breathe) and the Python API from
# the built module's docstrings. Every warning is an error (a broken link, a missing reference, a
# page in no toctree). Built afresh each time (-E, and no stale page left), dated by the last commit.
docs: configure
	@cmake --build $(BUILD) -j $(JOBS) --target nhdyn_python
	@rm -rf $(BUILD)/docs/html
	SOURCE_DATE_EPOCH=$$(git log -1 --format=%ct 2>/dev/null || echo 0) NHDYN_BUILD_DIR=$(abspath $(BUILD)) \
	  sphinx-build -E -W --keep-going -q -j $(JOBS) -b html -d $(BUILD)/docs/doctrees docs $(BUILD)/docs/html
	@echo "docs: open $(abspath $(BUILD))/docs/html/index.html"

# The fenced blocks after a `<!-- check: COMMAND -->` line show what COMMAND prints: this rewrites
# those that differ from a real run; ctest checks them (tests/docs/check_docs.py, label docs).
docs-update: configure
	@cmake --build $(BUILD) -j $(JOBS) --target nhdyn_cli
	python3 tests/docs/check_docs.py --nhdyn $(BUILD)/apps/nhdyn/nhdyn --update

package: build
	cd $(BUILD) && cpack -G DEB

bench: configure
	@cmake --build $(BUILD) -j $(JOBS) --target nhdyn_bench
	$(BUILD)/bench/nhdyn_bench --benchmark_min_time=0.2

# The performance guard (scripts/bench-check; docs/performance.md, "The guard").
BENCH_CHECK_TARGETS = nhdyn_cli nhdyn_sled_reference nhdyn_rattleback_reference nhdyn_bench_check
bench-check: configure
	@cmake --build $(BUILD) -j $(JOBS) --target $(BENCH_CHECK_TARGETS)
	python3 scripts/bench-check $(BUILD)

# The figures the performance page quotes (scripts/perf-figures; docs/performance.md, "The figures").
perf-figures: configure
	@cmake --build $(BUILD) -j $(JOBS) --target nhdyn_cli nhdyn_bench $(if $(wildcard $(BUILD)/python),nhdyn_python)
	python3 scripts/perf-figures $(BUILD) $(if $(QUICK),--quick)

bench-update: configure
	@cmake --build $(BUILD) -j $(JOBS) --target $(BENCH_CHECK_TARGETS)
	python3 scripts/bench-check $(BUILD) --update-docs $(if $(BASELINES),--update-baselines)

# The sanitizer build (docs/design.md, "Build and CI"): ASan + UBSan at -O1 with line tables only.
# With clang-14 installed it is also the fuzzer's build (every target instrumented for libFuzzer),
# so that the instrumented library is compiled once for both; otherwise GCC, without the fuzzer.
# The test folders that run the same kernels end to end (the CLI in child processes, long
# simulations of the gallery, studies, sweeps, the report in a browser) or check no code (layering)
# are left out of it:
# make test runs them; ASAN_SKIP_TESTS= (empty) builds and runs them all under the sanitizers.
SAN_BUILD ?= build-asan
ASAN_SKIP_TESTS ?= cli;gallery;studies;linearization;layering;report;codegen;jit;optimize
# Single tests of the remaining folders left out for the same reason (a regular expression for
# ctest -E; empty runs them): the bicycle's two 5 s roll kicks (10^4 right-hand sides of a kernel
# the shorter bicycle tests run too), every example loaded twice with each parameter as a value,
# the printer's sign test over every order of its symbols, and the quaternion rattleback's and
# gimbal lock's long runs beside the angle model (the shorter quaternion tests run the same kernels).
# Together nearly half of the sanitizer tests' time.
ASAN_SKIP_NAMES ?= ^WhippleBicycle[.]ARollKick|^RuntimeParameters[.]EveryExampleMatchesAModelCompiledWithTheValue$$|^EquationSigns[.]FunctionsOfNegatedSums|^QuaternionFrame[.](RattlebackFollows|PassesThroughTheOrientationWhereTheAnglesLock)
HAVE_CLANG := $(shell command -v clang++-14 >/dev/null 2>&1 && echo yes)
SAN_COMPILER = $(if $(HAVE_CLANG),-DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 -DNHDYN_FUZZ=ON)

# GiNaC's number library keeps global tables until exit: suppressed for LeakSanitizer (test
# discovery runs the executables at build time, so the build needs the same environment).
SANITIZER_ENV = ASAN_OPTIONS=detect_leaks=1 LSAN_OPTIONS=suppressions=$(CURDIR)/scripts/lsan.supp:print_suppressions=0 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

asan: deps
	@cmake -S . -B $(SAN_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Sanitize -DNHDYN_SANITIZE=ON -DNHDYN_BUILD_TESTS=ON \
	  -DNHDYN_BUILD_BENCH=OFF -DNHDYN_BUILD_CLI=$(if $(ASAN_SKIP_TESTS),OFF,ON) "-DNHDYN_SKIP_TEST_MODULES=$(ASAN_SKIP_TESTS)" $(SAN_COMPILER) \
	  $(if $(HAVE_CLANG),,-DNHDYN_WERROR=ON) >/dev/null
	@$(SANITIZER_ENV) cmake --build $(SAN_BUILD) -j $(JOBS)
	cd $(SAN_BUILD) && $(SANITIZER_ENV) ctest --output-on-failure -j $(JOBS) $(if $(ASAN_SKIP_NAMES),-E '$(ASAN_SKIP_NAMES)')

# Reuses build-asan when it was made with clang-14 (make asan), else configures build-fuzz.
# FUZZ_FLAGS: libFuzzer flags (CI gives -seed=1, so that its run tries the same inputs every time).
FUZZ_RUNS ?= 5000
FUZZ_FLAGS ?=
fuzz:
	NHDYN_FUZZ_BUILD=$(if $(HAVE_CLANG),$(CURDIR)/$(SAN_BUILD),$(CURDIR)/build-fuzz) sh fuzz/run $(FUZZ_RUNS) $(FUZZ_FLAGS)

clean:
	rm -rf $(BUILD) $(SAN_BUILD) build-fuzz results
