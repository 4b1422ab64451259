# capdyn build. `make help` lists the targets.
# Every library comes through pkg-config; dependencies are installed from
# Debian packages by scripts/install-deps.sh (`make deps`).

CC      ?= cc
CXX     ?= c++
BUILD   ?= build
PKGS_CORE = gsl ccd
PKGS_IO   = hdf5 tomlplusplus
WARN    = -Wall -Wextra -Wpedantic -Werror
OPT     ?= -O2 -g
CFLAGS_ALL   = -std=c99 $(WARN) $(OPT) -ffp-contract=off -Iinclude $(shell pkg-config --cflags $(PKGS_CORE) $(PKGS_IO) 2>/dev/null) $(EXTRA_CFLAGS)
CXXFLAGS_ALL = -std=c++17 $(WARN) $(OPT) -ffp-contract=off -Iinclude $(shell pkg-config --cflags $(PKGS_CORE) $(PKGS_IO) 2>/dev/null) $(EXTRA_CFLAGS)
LIBS_CORE = $(shell pkg-config --libs $(PKGS_CORE) 2>/dev/null) -lm
LIBS_IO   = $(shell pkg-config --libs $(PKGS_IO) 2>/dev/null)
LIBS_TEST = $(shell pkg-config --libs criterion 2>/dev/null)

CORE_SRC = $(wildcard src/math/*.c src/model/*.c src/dynamics/*.c src/contact/*.c src/mechanism/*.c src/sim/*.c)
IO_SRC_C = $(wildcard src/io/*.c)
IO_SRC_CXX = $(wildcard src/io/*.cpp)
CLI_SRC  = $(wildcard src/cli/*.c)
TEST_SRC = $(wildcard tests/*.c)
BENCH_SRC = $(wildcard bench/*.c)

CORE_OBJ = $(CORE_SRC:%.c=$(BUILD)/%.o)
IO_OBJ   = $(IO_SRC_C:%.c=$(BUILD)/%.o) $(IO_SRC_CXX:%.cpp=$(BUILD)/%.o)
CLI_OBJ  = $(CLI_SRC:%.c=$(BUILD)/%.o)
TEST_OBJ = $(TEST_SRC:%.c=$(BUILD)/%.o)

LIB      = $(BUILD)/libcapdyn.a
LIB_IO   = $(BUILD)/libcapdyn_io.a
CLI      = $(BUILD)/capdyn
TESTBIN  = $(BUILD)/capdyn_tests
JOBS    ?= 2

.PHONY: all deps lib cli test asan bench demo figures clean help check-deps

all: check-deps $(LIB) $(CLI)

help:
	@echo "make deps     install Debian packages (scripts/install-deps.sh)"
	@echo "make          build $(LIB) and $(CLI)"
	@echo "make test     install deps, build, run every test (Criterion)"
	@echo "make asan     the tests under AddressSanitizer + UndefinedBehaviorSanitizer"
	@echo "make bench    benchmarks (bench/)"
	@echo "make fuzz     libFuzzer targets, FUZZ_SECONDS=N each (fuzz/fuzz.mk; installs clang)"
	@echo "make demo     install deps, run the Fig. 5 envelope grasp and render its figures"
	@echo "make figures  run the paper scenarios, render PNG and SVG into figures/"

deps:
	@bash scripts/install-deps.sh

check-deps:
	@CAPDYN_NO_INSTALL=1 bash scripts/install-deps.sh || { echo "run 'make deps' first (or 'make test' / 'make demo', which install them)" >&2; exit 1; }

# tests (and only tests) may use POSIX/XSI extras: fork, kill, M_PI, ...
$(BUILD)/tests/%.o: tests/%.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -D_DEFAULT_SOURCE -MMD -MP -c $< -o $@

$(BUILD)/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -MMD -MP -c $< -o $@

$(BUILD)/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS_ALL) -MMD -MP -c $< -o $@

$(LIB): $(CORE_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^

$(LIB_IO): $(IO_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^

$(CLI): $(CLI_OBJ) $(LIB_IO) $(LIB)
	$(CXX) $(OPT) $(EXTRA_LDFLAGS) -o $@ $(CLI_OBJ) $(LIB_IO) $(LIB) $(LIBS_IO) $(LIBS_CORE)

# the failing-allocator test: its own executable (it interposes malloc)
FAILALLOC = $(BUILD)/capdyn_failalloc
$(FAILALLOC): tests/failalloc/failalloc.c $(LIB_IO) $(LIB)
	$(CC) $(CFLAGS_ALL) -MMD -MP -o $@ $< $(LIB_IO) $(LIB) $(LIBS_IO) $(LIBS_CORE) -lstdc++

$(TESTBIN): $(TEST_OBJ) $(LIB_IO) $(LIB)
	$(CXX) $(OPT) $(EXTRA_LDFLAGS) -o $@ $(TEST_OBJ) $(LIB_IO) $(LIB) $(LIBS_IO) $(LIBS_CORE) $(LIBS_TEST)

lib: $(LIB)
cli: $(CLI)

# The one test command (README, .ci/run): installs what is missing, builds,
# runs every Criterion test; Criterion prints its synthesis line.
test: deps
	@$(MAKE) --no-print-directory $(TESTBIN) $(CLI) $(FAILALLOC)
	CAPDYN_BIN=$(abspath $(CLI)) CAPDYN_ROOT=$(CURDIR) $(TESTBIN) --jobs $(JOBS) $(TEST_ARGS)
	CAPDYN_ROOT=$(CURDIR) $(FAILALLOC)

asan: deps
	@$(MAKE) --no-print-directory BUILD=build-asan OPT="-O1 -g -fno-omit-frame-pointer -fsanitize=address,undefined -fno-sanitize-recover=undefined" \
	  EXTRA_LDFLAGS="-fsanitize=address,undefined" build-asan/capdyn_tests build-asan/capdyn
	CAPDYN_BIN=$(abspath build-asan/capdyn) CAPDYN_ROOT=$(CURDIR) ASAN_OPTIONS=detect_leaks=1 \
	  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 build-asan/capdyn_tests --jobs $(JOBS) $(TEST_ARGS)

-include bench/bench.mk
-include fuzz/fuzz.mk

demo: deps
	@$(MAKE) --no-print-directory $(CLI)
	@bash plots/demo.sh

figures: deps
	@$(MAKE) --no-print-directory $(CLI)
	@bash plots/figures.sh

clean:
	rm -rf build build-asan build-fuzz figures

-include $(CORE_OBJ:.o=.d) $(IO_OBJ:.o=.d) $(CLI_OBJ:.o=.d) $(TEST_OBJ:.o=.d)
