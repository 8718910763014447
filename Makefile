# The two commands of the README's Quick start, and a few more for developers.
#   make run    install what is missing, build (Release), simulate the default example
#               (examples/sled.toml; MODEL=... NAME=... for another)
#   make test   install what is missing, build, run every test through ctest
BUILD ?= build
JOBS ?= $(shell nproc)
MODEL ?= examples/sled.toml
NAME ?= sled

.PHONY: run test build deps bench asan clean

deps:
	@bash scripts/install-deps

build: deps
	@cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release $(if $(CI),-DNHDYN_WERROR=ON) >/dev/null
	@cmake --build $(BUILD) -j $(JOBS)

run: build
	@mkdir -p results
	$(BUILD)/apps/nhdyn/nhdyn simulate $(MODEL) -o results/$(NAME).csv --plot results/$(NAME).png

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

bench: build
	$(BUILD)/bench/nhdyn_bench --benchmark_min_time=0.2

# GiNaC's number library keeps global tables until exit: suppressed for LeakSanitizer (test
# discovery runs the executables at build time, so the build needs the same environment).
SANITIZER_ENV = ASAN_OPTIONS=detect_leaks=1 LSAN_OPTIONS=suppressions=$(CURDIR)/scripts/lsan.supp:print_suppressions=0 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

# The tests again under AddressSanitizer and UndefinedBehaviorSanitizer (what CI runs too).
asan: deps
	@cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DNHDYN_SANITIZE=ON \
	  -DNHDYN_WERROR=ON -DNHDYN_BUILD_BENCH=OFF >/dev/null
	@$(SANITIZER_ENV) cmake --build build-asan -j $(JOBS)
	cd build-asan && $(SANITIZER_ENV) ctest --output-on-failure -j $(JOBS)

clean:
	rm -rf $(BUILD) build-asan results
