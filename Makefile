# SPDX-License-Identifier: Apache-2.0
# canola -- the commands of the README. Everything builds out of tree with CMake.
#   make demo    the demo network (canola demo, from the Python environment)
#   make demo-c  the C demo network on the simulated bus, as a candump log
#   make test    every test stage (tests/run-stages), then one summary table
#   make check   the fast inner loop: plain build + ctest, the fast Python tests
#   make bench   instruction counts (valgrind) as a Markdown table (BENCH_QUICK=1: quick)
#   make run-firmware  the Cortex-M4 example image in QEMU on the software bus (Ctrl-C stops)
#   make format  rewrite the sources with clang-format

BUILD      ?= build
BUILD_SAN  ?= build-san
CMAKE_GEN  := $(shell command -v ninja >/dev/null 2>&1 && echo "-G Ninja")
# Tests run side by side, counted from the machine's cores: most of the C tests' and Python
# tests' time is waiting, so pytest runs two workers a core.
JOBS       ?= $(shell nproc 2>/dev/null || echo 2)
PY_WORKERS ?= $(shell echo $$((2 * $(JOBS))))
# Hand-written C only: generated golden files (python/tests/golden) keep the generator's layout.
FORMAT_SRC  = $(shell git ls-files '*.c' '*.h' ':!python' 2>/dev/null || find include src port tests examples bench -name '*.[ch]')

.PHONY: all demo demo-c test check test-plain test-san test-configs test-python test-pytest \
        test-pytest-fast test-python-lint test-view test-vcan format format-check bench fuzz fuzz-c \
        fuzz-long fuzz-eds fuzz-gateway fuzz-socketcand coverage py-env lint cortex-m test-m32 \
        test-clang analyse clean fuzz-conformance firmware run-firmware test-firmware

all: $(BUILD)/build.stamp

$(BUILD)/build.stamp: FORCE
	@cmake -S . -B $(BUILD) $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
	@cmake --build $(BUILD)

demo-c: all
	./$(BUILD)/sim_network

# Every stage runs, even after one failed; tests/run-stages prints the summary table
# (SKIP="vcan san" make test leaves stages out).
test:
	@tests/run-stages

check:
	@tests/run-stages plain pytest-fast

test-plain:
	cmake -S . -B $(BUILD) $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
	cmake --build $(BUILD)
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

test-san:
	cmake -S . -B $(BUILD_SAN) $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=Debug -DCANOLA_SANITIZE=ON >/dev/null
	cmake --build $(BUILD_SAN)
	cd $(BUILD_SAN) && UBSAN_OPTIONS=print_stacktrace=1 ctest --output-on-failure -j $(JOBS)

# The core must build warning-free with every configuration in configs/ (and clang's view).
test-configs:
	@rc=0; for cfg in configs/*.h; do \
	  name=$$(basename $$cfg .h); \
	  if cmake -S . -B build-config-$$name $(CMAKE_GEN) -DCANOLA_TESTS=OFF \
	       -DCANOLA_CONFIG_FILE=$(CURDIR)/$$cfg >/dev/null && \
	     cmake --build build-config-$$name --target canola >/dev/null; then \
	    echo "config $$name: core builds"; else echo "config $$name: FAILED"; rc=1; fi; \
	done; \
	if command -v clang >/dev/null 2>&1; then \
	  ok=1; for f in src/*.c; do \
	    clang -std=c11 -Wall -Wextra -Wconversion -Wshadow -Werror -pedantic -Iinclude -Isrc \
	      -fsyntax-only $$f || ok=0; \
	  done; \
	  if [ $$ok = 1 ]; then echo "clang: core builds"; else echo "clang: FAILED"; rc=1; fi; \
	else echo "clang: NOT RUN (not installed; .ci/run installs it)"; fi; \
	exit $$rc

# The Python package (python/): its own virtual environment, pinned tools, pytest, ruff, mypy.
# Installed again (the cffi extension rebuilt) when the package's build inputs change.
PY_VENV = build-py/venv
PY_INPUTS = python/pyproject.toml python/setup.py python/src/canola/_build_core.py \
            $(wildcard port/python/*.[ch]) \
            $(wildcard src/*.[ch] include/canola/*.h port/sim/*.[ch] port/linux/file_storage.c) \
            $(wildcard port/linux/transport.c port/linux/socketcan*.c port/linux/canola/*.h)
py-env: build-py/env.stamp
build-py/env.stamp: $(PY_INPUTS)
	@test -x $(PY_VENV)/bin/python || python3 -m venv $(PY_VENV)
	$(PY_VENV)/bin/python -m pip install -q --disable-pip-version-check -e 'python[test]'
	@touch $@

# The README's main command: a master and three devices through boot-up, the CiA 302-2 manager,
# SYNC and PDOs, EMCY and heartbeat loss, decoded and checked (canola demo --help).
demo:
	@test -x $(PY_VENV)/bin/canola || $(MAKE) --no-print-directory py-env
	$(PY_VENV)/bin/canola demo

# pytest (markers in python/pyproject.toml: slow, realtime, vcan), then ruff and mypy.
test-python: test-pytest test-python-lint

test-pytest: py-env
	cd python && ../$(PY_VENV)/bin/python -m pytest -q -n $(PY_WORKERS) tests

# make check's share: the tests not marked slow.
test-pytest-fast: py-env
	cd python && ../$(PY_VENV)/bin/python -m pytest -q -n $(PY_WORKERS) -m 'not slow' tests

# canola view in a real browser (python/tests/test_view_browser.py): Debian's chromium,
# headless; the demo's page saved as build-logs/view.png. NOT RUN without chromium.
test-view: py-env
	@if command -v chromium >/dev/null 2>&1 || [ -n "$$CANOLA_CHROMIUM" ]; then \
	  cd python && CANOLA_BROWSER_TESTS=1 ../$(PY_VENV)/bin/python -m pytest -q \
	    tests/test_view_browser.py; \
	else echo "canola view in a browser: NOT RUN (chromium not installed; .ci/run installs it)"; fi

# ruff over every Python file of the repository (the benches, fuzzers, firmware tests and
# tools as well as the package; build folders are git-ignored), with the package's settings;
# mypy --strict over the package.
test-python-lint: py-env
	cd python && ../$(PY_VENV)/bin/ruff check --config pyproject.toml .. && \
	  ../$(PY_VENV)/bin/mypy --strict src

# Coverage of the core by the C tests (gcovr from the Python environment's pinned tools).
# Prints the summary lines; fails when branch coverage of src/ is below COV_BRANCH_MIN %.
# The profile tests build src/ a second and third time in other configurations, where a
# left-out feature's stand-in of a function sits on another line: functions are merged
# separately (--merge-mode-functions=separate), lines and branches as usual. The profiles'
# -Os copies (test_profile_*_os, and the firmware builds canola_fw_* the size rows measure:
# size builds, where inlining multiplies a line's branches per call site) are left out
# (--exclude-directories): coverage is of the -O0 builds.
COV_BRANCH_MIN ?= 95
coverage: py-env
	cmake -S . -B build-cov $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=Debug -DCMAKE_C_FLAGS="--coverage -O0" \
	  -DCMAKE_EXE_LINKER_FLAGS=--coverage >/dev/null
	cmake --build build-cov >/dev/null
	find build-cov -name '*.gcda' -delete
	cd build-cov && ctest >/dev/null
	@$(PY_VENV)/bin/gcovr -r . --filter 'src/' --print-summary --merge-mode-functions=separate \
	  --exclude-directories 'build-cov/tests/CMakeFiles/[a-z_]+_os[a-z_]*\.dir' \
	  --exclude-directories 'build-cov/tests/CMakeFiles/(canola|test)_fw_[a-z_]+\.dir' \
	  --fail-under-branch $(COV_BRANCH_MIN) build-cov > build-cov/coverage.txt; rc=$$?; \
	  tail -n 3 build-cov/coverage.txt; \
	  if [ $$rc -ne 0 ]; then echo "coverage: branches below $(COV_BRANCH_MIN) % (gcovr exit $$rc)"; fi; \
	  exit $$rc

# libFuzzer (clang): the frame input path (node), the SDO client against a hostile server
# (sdo_client), the CiA 302-2 manager against hostile slaves (manager) and the socketcand
# client of port/linux against a hostile server (socketcand_client); atheris on the EDS/DCF
# parser (fuzz/fuzz_eds.py), the CiA 309-3 gateway's line parser (fuzz/fuzz_gateway_parser.py)
# and the socketcand protocol parser of the hub (fuzz/fuzz_socketcand.py) in the Python
# environment (the package's 'fuzz' extra pins atheris).
# Each target replays its seed corpus (fuzz/corpus/<target>/), then fuzzes for FUZZ_SECONDS.
# New inputs go to build-fuzz/corpus-<target>/; a finding is a crash file in build-fuzz/
# (turn it into a regression test). For hours: make fuzz-long (below), docs/security.md.
FUZZ_SECONDS ?= 30
FUZZ_TARGETS = node sdo_client manager socketcand_client
FUZZ_FLAGS = -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all
FUZZ_EXTRA_node = examples/example_od.c
FUZZ_EXTRA_sdo_client = examples/example_od.c
FUZZ_EXTRA_manager = examples/example_od.c
FUZZ_EXTRA_socketcand_client = port/linux/socketcand.c port/linux/transport.c
fuzz: fuzz-c fuzz-eds fuzz-gateway fuzz-socketcand fuzz-conformance

build-fuzz/fuzz_%: FORCE
	@mkdir -p build-fuzz
	@clang $(FUZZ_FLAGS) -Iinclude -Isrc -Iexamples -Iport/linux src/*.c $(FUZZ_EXTRA_$*) \
	  fuzz/fuzz_$*.c -o $@

fuzz-c: $(FUZZ_TARGETS:%=build-fuzz/fuzz_%)
	@for t in $(FUZZ_TARGETS); do \
	  mkdir -p build-fuzz/corpus-$$t && \
	  build-fuzz/fuzz_$$t -artifact_prefix=build-fuzz/ fuzz/corpus/$$t/* >/dev/null 2>&1 || \
	    { echo "fuzz_$$t: the seed corpus fails"; exit 1; }; \
	  build-fuzz/fuzz_$$t -artifact_prefix=build-fuzz/ -max_total_time=$(FUZZ_SECONDS) \
	    -print_final_stats=1 build-fuzz/corpus-$$t fuzz/corpus/$$t > build-fuzz/fuzz-$$t.log 2>&1; \
	  rc=$$?; tail -n 4 build-fuzz/fuzz-$$t.log; echo "fuzz_$$t: exit $$rc"; \
	  [ $$rc -eq 0 ] || exit $$rc; \
	done

# Every target (C and Python) for FUZZ_LONG_SECONDS each, one after the other, then one
# table: executions, coverage, corpus, findings (fuzz/run-long; logs in build-fuzz/long/).
FUZZ_LONG_SECONDS ?= 600
FUZZ_LONG_TARGETS ?= $(FUZZ_TARGETS) eds gateway socketcand conformance
fuzz-long: py-env $(FUZZ_TARGETS:%=build-fuzz/fuzz_%)
	@$(PY_VENV)/bin/python -c 'import atheris' 2>/dev/null || \
	  $(PY_VENV)/bin/python -m pip install -q --disable-pip-version-check -e 'python[fuzz]' \
	  >/dev/null 2>&1 || echo "fuzz-long: atheris not installable here: Python targets NOT RUN"
	@fuzz/run-long $(FUZZ_LONG_SECONDS) $(FUZZ_LONG_TARGETS)

# atheris has no wheel for every Python: without it these targets still replay their seed
# corpus (fuzz_eds: the EDS parser; fuzz_conformance: the conformance tester against a
# node whose answers are the fuzzer's).
fuzz-eds fuzz-conformance: fuzz-%: py-env
	@mkdir -p build-fuzz/corpus-$*
	@$(PY_VENV)/bin/python -c 'import atheris' 2>/dev/null || \
	  $(PY_VENV)/bin/python -m pip install -q --disable-pip-version-check -e 'python[fuzz]' \
	  >/dev/null 2>&1 || echo "fuzz_$*: atheris not installable here: replaying the corpus only"
	@$(PY_VENV)/bin/python fuzz/fuzz_$*.py -artifact_prefix=build-fuzz/ \
	  -max_total_time=$(FUZZ_SECONDS) build-fuzz/corpus-$* fuzz/corpus/$* \
	  > build-fuzz/fuzz-$*.log 2>&1; rc=$$?; tail -n 4 build-fuzz/fuzz-$*.log; \
	  echo "fuzz_$*: exit $$rc"; exit $$rc

fuzz-gateway: py-env
	@mkdir -p build-fuzz/corpus-gateway
	@$(PY_VENV)/bin/python -c 'import atheris' 2>/dev/null || \
	  $(PY_VENV)/bin/python -m pip install -q --disable-pip-version-check -e 'python[fuzz]' >/dev/null 2>&1; \
	  if ! $(PY_VENV)/bin/python -c 'import atheris' 2>/dev/null; then \
	    echo "fuzz_gateway: NOT RUN (atheris not installable; tests/test_gateway_parser.py fuzzes by random lines)"; \
	    exit 0; fi; \
	  $(PY_VENV)/bin/python fuzz/fuzz_gateway_parser.py -artifact_prefix=build-fuzz/ \
	  -max_total_time=$(FUZZ_SECONDS) -dict=fuzz/gateway.dict \
	  build-fuzz/corpus-gateway fuzz/corpus/gateway > build-fuzz/fuzz-gateway.log 2>&1; \
	  rc=$$?; grep -E '^#[0-9]+[[:space:]]+(INITED|DONE)' build-fuzz/fuzz-gateway.log; \
	  tail -n 1 build-fuzz/fuzz-gateway.log; echo "fuzz_gateway: exit $$rc"; exit $$rc

fuzz-socketcand: py-env
	@mkdir -p build-fuzz/corpus-socketcand
	@$(PY_VENV)/bin/python -c 'import atheris' 2>/dev/null || \
	  $(PY_VENV)/bin/python -m pip install -q --disable-pip-version-check -e 'python[fuzz]' >/dev/null 2>&1; \
	  if ! $(PY_VENV)/bin/python -c 'import atheris' 2>/dev/null; then \
	    echo "fuzz_socketcand: NOT RUN (atheris not installable; tests/test_socketcand.py covers the parser)"; \
	    exit 0; fi; \
	  $(PY_VENV)/bin/python fuzz/fuzz_socketcand.py -artifact_prefix=build-fuzz/ \
	  -max_total_time=$(FUZZ_SECONDS) build-fuzz/corpus-socketcand fuzz/corpus/socketcand \
	  > build-fuzz/fuzz-socketcand.log 2>&1; \
	  rc=$$?; tail -n 4 build-fuzz/fuzz-socketcand.log; echo "fuzz_socketcand: exit $$rc"; exit $$rc

# Static analysis of the core (src/, include/), warnings as errors: cppcheck (default and
# multi-channel configuration) and clang-tidy (.clang-tidy). .ci/run installs both.
LINT_CFLAGS = -std=c11 -Iinclude -Isrc
lint:
	@command -v cppcheck >/dev/null || { echo "lint: cppcheck missing (.ci/run installs it)"; exit 1; }
	@command -v clang-tidy >/dev/null || { echo "lint: clang-tidy missing (.ci/run installs it)"; exit 1; }
	cppcheck --std=c11 --enable=warning,style,performance,portability --error-exitcode=1 -q \
	  --inline-suppr --suppressions-list=.cppcheck-suppressions -Iinclude -Isrc -UCO_CONFIG_FILE \
	  src/*.c
	cppcheck --std=c11 --enable=warning,style,performance,portability --error-exitcode=1 -q \
	  --inline-suppr --suppressions-list=.cppcheck-suppressions -Iinclude -Isrc -UCO_CONFIG_FILE \
	  -DCO_SDO_CLIENTS_MAX=4 -DCO_SDO_SERVERS_MAX=4 src/*.c
	@echo "cppcheck: clean"
	@printf '%s\n' src/*.c | xargs -P 2 -I{} clang-tidy --quiet {} -- $(LINT_CFLAGS) 2>/dev/null \
	  > build-lint.log; rc=$$?; grep -E 'warning:|error:' build-lint.log; rm -f build-lint.log; \
	  [ $$rc -eq 0 ] && echo "clang-tidy: clean" || { echo "clang-tidy: findings above"; exit 1; }

# The core for a Cortex-M4 (arm-none-eabi-gcc): the strictest warnings, no host headers.
ARM_FLAGS = -std=c11 -mcpu=cortex-m4 -mthumb -Os -ffreestanding -Wall -Wextra -Wconversion \
            -Wshadow -Wcast-align -Werror -pedantic -Iinclude -Isrc
# port/cortex-m (CAN side, main loop, time base, flash storage) and the STM32 drivers, for a
# Cortex-M0 and a Cortex-M4.
ARM_PORT_FLAGS = -std=c11 -mthumb -Os -ffreestanding -Wall -Wextra -Wconversion -Wshadow \
                 -Wcast-align -Werror -pedantic -Iinclude -Iport/cortex-m -Iport/stm32
ARM_PORT_SRC = $(wildcard port/cortex-m/*.c port/stm32/*.c)
cortex-m:
	@if command -v arm-none-eabi-gcc >/dev/null 2>&1; then \
	  mkdir -p build-arm && for f in src/*.c; do \
	    arm-none-eabi-gcc $(ARM_FLAGS) -c $$f -o build-arm/$$(basename $$f .c).o || exit 1; \
	  done && arm-none-eabi-gcc $(ARM_FLAGS) -DCO_CONFIG_FILE='"'$(CURDIR)/configs/minimal.h'"' \
	    -c src/node.c -o build-arm/node-minimal.o && for f in src/od*.c; do \
	    arm-none-eabi-gcc $(ARM_FLAGS) -DCO_CONFIG_OD_COMPACT=1 -c $$f \
	      -o build-arm/$$(basename $$f .c)-compact.o || exit 1; \
	  done && for cpu in cortex-m0 cortex-m4; do for f in $(ARM_PORT_SRC); do \
	    arm-none-eabi-gcc $(ARM_PORT_FLAGS) -mcpu=$$cpu -c $$f -o build-arm/$$cpu-$$(basename $$f .c).o \
	      || exit 1; \
	  done; done && echo "cortex-m: core builds (-Werror -pedantic -Wconversion)" && \
	  echo "cortex-m: port/cortex-m CAN side and port/stm32 drivers build for M0 and M4"; \
	else echo "cortex-m: SKIPPED (arm-none-eabi-gcc not installed; .ci/run installs it as root)"; fi

# The QEMU example firmware (examples/firmware, docs/firmware.md): a Cortex-M4 image
# (mps2-an386) and a Cortex-M0 one (microbit) into build-fw/BOARD/. make run-firmware boots
# the M4 one on the software bus and prints its URL; make test-firmware boots both and runs
# tests/firmware (conformance with every check, the manager from a DCF, stored parameters
# across a reset, python-canopen): NOT RUN without arm-none-eabi-gcc or qemu-system-arm.
FW_BOARDS = mps2-an386 microbit
FW_MAKE = $(MAKE) -s -C examples/firmware OUT=$(CURDIR)/build-fw PYTHON=$(CURDIR)/$(PY_VENV)/bin/python
firmware: py-env
	@for b in $(FW_BOARDS); do $(FW_MAKE) BOARD=$$b || exit 1; done

run-firmware: py-env
	@$(FW_MAKE) BOARD=mps2-an386 >/dev/null
	@$(PY_VENV)/bin/python examples/firmware/qemu_rig.py build-fw/mps2-an386/firmware.elf

test-firmware: py-env
	@if ! command -v arm-none-eabi-gcc >/dev/null 2>&1; then \
	  echo "firmware: NOT RUN (arm-none-eabi-gcc not installed; .ci/run installs it)"; \
	elif ! command -v qemu-system-arm >/dev/null 2>&1; then \
	  echo "firmware: NOT RUN (qemu-system-arm not installed; .ci/run installs it)"; \
	else $(MAKE) -s firmware && $(PY_VENV)/bin/python -m pytest -q -p no:cacheprovider \
	  --rootdir tests/firmware -n 2 --dist loadscope tests/firmware; fi

# A 32-bit host build of the core and the tests (gcc -m32, from gcc-multilib), tests run.
test-m32:
	@if echo 'int main(void){return 0;}' | gcc -m32 -x c - -o /dev/null 2>/dev/null; then \
	  cmake -S . -B build-m32 $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=Debug -DCMAKE_C_FLAGS=-m32 \
	    -DCMAKE_EXE_LINKER_FLAGS=-m32 >/dev/null && cmake --build build-m32 >/dev/null && \
	  cd build-m32 && ctest --output-on-failure; \
	else echo "test-m32: SKIPPED (gcc -m32 cannot link: apt-get install gcc-multilib)"; fi

# The same tests built by clang (the normal build uses the system cc, gcc).
test-clang:
	CC=clang cmake -S . -B build-clang $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
	cmake --build build-clang >/dev/null
	cd build-clang && ctest --output-on-failure

# Everything above: what .ci/run adds to make test.
analyse: lint cortex-m test-m32 test-clang

# The SocketCAN tier (tests/linux/vcan-tier.sh): the C SocketCAN test, canola-node with
# candump/cansend, and pytest -m vcan, on vcan0 natively when the kernel has it, else in
# one canvm run (CANOLA_CANVM, else ../shared/tools/canvm/canvm), else reported NOT RUN.
# It needs the Python environment (canola device, pytest -m vcan) complete before it starts.
test-vcan: py-env
	cmake -S . -B $(BUILD) $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
	cmake --build $(BUILD) --target test_socketcan canola-node
	tests/linux/run-vcan-tier $(BUILD)

format-check:
	@if command -v clang-format >/dev/null 2>&1; then \
	  clang-format --dry-run --Werror $(FORMAT_SRC) && echo "format check: ok"; \
	else \
	  echo "format check: NOT RUN (clang-format not installed; .ci/run installs it)"; \
	fi

format:
	clang-format -i $(FORMAT_SRC)

# BENCH_QUICK=1: every row with a fraction of the work (CI checks that the bench runs).
bench:
	BENCH_QUICK=$(BENCH_QUICK) ./bench/run

clean:
	rm -rf $(BUILD) $(BUILD_SAN) build-logs build-load build-bench build-config-* build-py build-cov build-fuzz build-vcan build-arm build-m32 build-clang build-fw

FORCE:
