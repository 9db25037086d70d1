# canola -- the commands of the README. Everything builds out of tree with CMake.
#   make demo    the demo network on the simulated bus
#   make test    every test: normal build, ASan+UBSan build, format check
#   make bench   instruction counts (valgrind) as a Markdown table
#   make format  rewrite the sources with clang-format

BUILD      ?= build
BUILD_SAN  ?= build-san
CMAKE_GEN  := $(shell command -v ninja >/dev/null 2>&1 && echo "-G Ninja")
# Hand-written C only: generated golden files (python/tests/golden) keep the generator's layout.
FORMAT_SRC  = $(shell git ls-files '*.c' '*.h' ':!python' 2>/dev/null || find include src port tests examples bench -name '*.[ch]')

.PHONY: all demo test test-plain test-san test-configs test-python format format-check bench fuzz clean

all: $(BUILD)/build.stamp

$(BUILD)/build.stamp: FORCE
	@cmake -S . -B $(BUILD) $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
	@cmake --build $(BUILD)

demo: all
	./$(BUILD)/sim_network

test: test-plain test-san test-configs test-python format-check

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

# The Python package (python/): its own virtual environment, pinned tools, pytest, ruff, mypy.
PY_VENV = build-py/venv
test-python:
	@test -x $(PY_VENV)/bin/python || python3 -m venv $(PY_VENV)
	$(PY_VENV)/bin/python -m pip install -q --disable-pip-version-check -e 'python[test]'
	cd python && ../$(PY_VENV)/bin/python -m pytest -q tests
	cd python && ../$(PY_VENV)/bin/ruff check . && ../$(PY_VENV)/bin/mypy --strict src

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

format-check:
	@if command -v clang-format >/dev/null 2>&1; then \
	  clang-format --dry-run --Werror $(FORMAT_SRC) && echo "format check: ok"; \
	else \
	  echo "format check: SKIPPED (clang-format not installed; .ci/run installs it)"; \
	fi

format:
	clang-format -i $(FORMAT_SRC)

bench:
	./bench/run

clean:
	rm -rf $(BUILD) $(BUILD_SAN) build-bench build-config-* build-py

FORCE:
