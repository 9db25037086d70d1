# canola -- the commands of the README. Everything builds out of tree with CMake.
#   make demo    the demo network on the simulated bus
#   make test    every test: normal build, ASan+UBSan build, format check
#   make bench   instruction counts (valgrind) as a Markdown table (BENCH_QUICK=1: quick)
#   make format  rewrite the sources with clang-format

BUILD      ?= build
BUILD_SAN  ?= build-san
CMAKE_GEN  := $(shell command -v ninja >/dev/null 2>&1 && echo "-G Ninja")
# Hand-written C only: generated golden files (python/tests/golden) keep the generator's layout.
FORMAT_SRC  = $(shell git ls-files '*.c' '*.h' ':!python' 2>/dev/null || find include src port tests examples bench -name '*.[ch]')

.PHONY: all demo test test-plain test-san test-configs test-python test-vcan format format-check bench fuzz fuzz-gateway coverage py-env clean

all: $(BUILD)/build.stamp

$(BUILD)/build.stamp: FORCE
	@cmake -S . -B $(BUILD) $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
	@cmake --build $(BUILD)

demo: all
	./$(BUILD)/sim_network

test: test-plain test-san test-configs test-python test-vcan format-check

test-plain:
	cmake -S . -B $(BUILD) $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
	cmake --build $(BUILD)
	cd $(BUILD) && ctest --output-on-failure

test-san:
	cmake -S . -B $(BUILD_SAN) $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=Debug -DCANOLA_SANITIZE=ON >/dev/null
	cmake --build $(BUILD_SAN)
	cd $(BUILD_SAN) && UBSAN_OPTIONS=print_stacktrace=1 ctest --output-on-failure

# The core must build warning-free with every configuration in configs/.
test-configs:
	@for cfg in configs/*.h; do \
	  name=$$(basename $$cfg .h); \
	  cmake -S . -B build-config-$$name $(CMAKE_GEN) -DCANOLA_TESTS=OFF \
	    -DCANOLA_CONFIG_FILE=$(CURDIR)/$$cfg >/dev/null && \
	  cmake --build build-config-$$name --target canola >/dev/null && \
	  echo "config $$name: core builds" || exit 1; \
	done
	@if command -v clang >/dev/null 2>&1; then \
	  for f in src/*.c; do \
	    clang -std=c11 -Wall -Wextra -Wconversion -Wshadow -Werror -pedantic -Iinclude -Isrc \
	      -fsyntax-only $$f || exit 1; \
	  done && echo "clang: core builds"; \
	else echo "clang: SKIPPED (not installed; .ci/run installs it)"; fi

# The Python package (python/): its own virtual environment, pinned tools, pytest, ruff, mypy.
PY_VENV = build-py/venv
py-env:
	@test -x $(PY_VENV)/bin/python || python3 -m venv $(PY_VENV)
	$(PY_VENV)/bin/python -m pip install -q --disable-pip-version-check -e 'python[test]'

test-python: py-env
	cd python && ../$(PY_VENV)/bin/python -m pytest -q tests
	cd python && ../$(PY_VENV)/bin/ruff check . && ../$(PY_VENV)/bin/mypy --strict src

# Coverage of the core by the C tests (gcovr from the Python environment's pinned tools).
coverage: py-env
	cmake -S . -B build-cov $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=Debug -DCMAKE_C_FLAGS="--coverage -O0" \
	  -DCMAKE_EXE_LINKER_FLAGS=--coverage >/dev/null
	cmake --build build-cov >/dev/null
	find build-cov -name '*.gcda' -delete
	cd build-cov && ctest >/dev/null
	$(PY_VENV)/bin/gcovr -r . --filter 'src/' --print-summary build-cov | tail -n 3

# libFuzzer (clang) on the frame input path: replay the seed corpus, then fuzz for a while.
# New inputs go to build-fuzz/; a finding is a crash file there (turn it into a test).
FUZZ_SECONDS ?= 30
FUZZ_FLAGS = -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all
fuzz:
	@mkdir -p build-fuzz/corpus-node
	clang $(FUZZ_FLAGS) -Iinclude -Isrc -Iexamples src/*.c examples/example_od.c \
	  fuzz/fuzz_node.c -o build-fuzz/fuzz_node
	build-fuzz/fuzz_node -artifact_prefix=build-fuzz/ fuzz/corpus/node/*
	@build-fuzz/fuzz_node -artifact_prefix=build-fuzz/ -max_total_time=$(FUZZ_SECONDS) \
	  -print_final_stats=1 \
	  build-fuzz/corpus-node fuzz/corpus/node > build-fuzz/fuzz.log 2>&1; rc=$$?; \
	  tail -n 8 build-fuzz/fuzz.log; echo "fuzz_node: exit $$rc"; exit $$rc

# atheris on the CiA 309-3 gateway's line parser (the 'fuzz' extra of the Python package).
fuzz-gateway: py-env
	$(PY_VENV)/bin/python -m pip install -q --disable-pip-version-check -e 'python[fuzz]'
	@mkdir -p build-fuzz/corpus-gateway
	$(PY_VENV)/bin/python fuzz/fuzz_gateway_parser.py -artifact_prefix=build-fuzz/ \
	  -max_total_time=$(FUZZ_SECONDS) build-fuzz/corpus-gateway

# The SocketCAN tier (tests/linux/vcan-tier.sh): the C SocketCAN test, canola-node with
# candump/cansend, and pytest -m vcan, on vcan0 natively when the kernel has it, else in
# one canvm run (../shared/tools/canvm), else reported NOT RUN.
test-vcan:
	cmake -S . -B $(BUILD) $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
	cmake --build $(BUILD) --target test_socketcan canola-node
	tests/linux/run-vcan-tier $(BUILD)

format-check:
	@if command -v clang-format >/dev/null 2>&1; then \
	  clang-format --dry-run --Werror $(FORMAT_SRC) && echo "format check: ok"; \
	else \
	  echo "format check: SKIPPED (clang-format not installed; .ci/run installs it)"; \
	fi

format:
	clang-format -i $(FORMAT_SRC)

# BENCH_QUICK=1: every row with a fraction of the work (CI checks that the bench runs).
bench:
	BENCH_QUICK=$(BENCH_QUICK) ./bench/run

clean:
	rm -rf $(BUILD) $(BUILD_SAN) build-bench build-config-* build-py build-cov build-fuzz build-vcan

FORCE:
