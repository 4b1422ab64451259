# capdyn build. `make help` lists the targets.
# Every library comes through pkg-config; dependencies are installed from
# Debian packages by scripts/install-deps.sh (`make deps`).

CC      ?= cc
CXX     ?= c++
# MPI=1: capdyn sweep also under mpirun/srun (docs/sweep.md), in its own
# build directory; Open MPI from scripts/install-mpi-deps.sh (make mpi-deps)
ifeq ($(MPI),1)
BUILD   ?= build-mpi
endif
BUILD   ?= build
PKGS_CORE = gsl ccd
PKGS_IO   = hdf5 zlib tomlplusplus qhull_r urdfdom
ifeq ($(MPI),1)
PKGS_IO  += ompi-c
EXTRA_CFLAGS += -DCAPDYN_MPI
endif
# WERROR=0 turns -Werror off (a sanitizer build may meet a compiler's false
# warning, e.g. -Wmaybe-uninitialized under -fsanitize=thread); on by default
WERROR  ?= 1
WARN    = -Wall -Wextra -Wpedantic $(if $(filter 1,$(WERROR)),-Werror)
# -O3: the same results bit for bit as -O2 (no -ffast-math, and
# -ffp-contract=off below: no reassociation, no fused multiply-add), and
# 1.08-1.29x faster on the shipped scenarios (docs/performance.md section 13:
# ROUNDS=9 bash bench/ab.sh with bench_scenarios built at -O2 and at -O3).
# The build does not track flags: after changing OPT, make clean.
OPT     ?= -O3 -g
CFLAGS_ALL   = -std=c99 $(WARN) $(OPT) -ffp-contract=off -Iinclude $(shell pkg-config --cflags $(PKGS_CORE) $(PKGS_IO) 2>/dev/null) $(EXTRA_CFLAGS)
CXXFLAGS_ALL = -std=c++17 $(WARN) $(OPT) -ffp-contract=off -Iinclude $(shell pkg-config --cflags $(PKGS_CORE) $(PKGS_IO) 2>/dev/null) $(EXTRA_CFLAGS)
LIBS_CORE = $(shell pkg-config --libs $(PKGS_CORE) 2>/dev/null) -lm
LIBS_IO   = $(shell pkg-config --libs $(PKGS_IO) 2>/dev/null)
LIBS_TEST = $(shell pkg-config --libs criterion 2>/dev/null)

CORE_SRC = $(wildcard src/math/*.c src/model/*.c src/builders/*.c src/data/*.c src/kinematics/*.c src/dynamics/*.c src/contact/*.c src/mechanism/*.c src/sim/*.c src/control/*.c)
IO_SRC_C = $(wildcard src/io/*.c src/analysis/*.c)
IO_SRC_CXX = $(wildcard src/io/*.cpp)
CLI_SRC  = $(wildcard src/cli/*.c) src/fmu/vars.c src/fmu/zip.c
TEST_SRC = $(wildcard tests/*.c)
BENCH_SRC = $(wildcard bench/*.c)
EXAMPLE_SRC = $(wildcard examples/*.c)

CORE_OBJ = $(CORE_SRC:%.c=$(BUILD)/%.o)
IO_OBJ   = $(IO_SRC_C:%.c=$(BUILD)/%.o) $(IO_SRC_CXX:%.cpp=$(BUILD)/%.o)
CLI_OBJ  = $(CLI_SRC:%.c=$(BUILD)/%.o)
TEST_OBJ = $(TEST_SRC:%.c=$(BUILD)/%.o)

LIB      = $(BUILD)/libcapdyn.a
LIB_IO   = $(BUILD)/libcapdyn_io.a
CLI      = $(BUILD)/capdyn
TESTBIN  = $(BUILD)/capdyn_tests
EXAMPLES = $(EXAMPLE_SRC:examples/%.c=$(BUILD)/examples/%)
JOBS    ?= 2
# the FMU binary (issue 20, docs/fmu.md; rules below "the FMU binary"):
# FMI 2.0 headers from fmpy in the venv, when it is installed
VENV    ?= $(BUILD)/venv
FMI2_HDR_DIR = $(firstword $(wildcard $(VENV)/lib/python3*/site-packages/fmpy/c-code))
FMU_DIR  = $(BUILD)/fmu/linux64
FMU_SO   = $(FMU_DIR)/capdyn_fmu.so
FMU_OBJ  = $(BUILD)/fmu/obj/fmu.o $(BUILD)/fmu/obj/vars.o

.PHONY: all fmu deps mpi-deps lib cli shared examples test test-long doctest python-test gltf-test plots-test asan tsan bench demo figures capture-map clean help check-deps install uninstall install-check

all: check-deps $(LIB) $(CLI) shared $(if $(FMI2_HDR_DIR),$(FMU_SO))

help:
	@echo "make deps     install Debian packages (scripts/install-deps.sh)"
	@echo "make          build $(LIB), $(LIB_IO), their shared libraries (.so) and $(CLI)"
	@echo "make test     install deps, build, run every test but the long ones (Criterion), every example, the Python suite, the doc tests"
	@echo "make test-long  the long physics regressions and doc examples (minutes; .ci/run runs it)"
	@echo "make doctest  only the doc tests: every shell block of README.md and docs/ (tests/doctest/run.sh)"
	@echo "make examples build examples/*.c into $(BUILD)/examples/"
	@echo "make asan     the tests of make test under AddressSanitizer + UndefinedBehaviorSanitizer (ASAN_LONG=1: the long ones too)"
	@echo "make tsan     two threads on one model under ThreadSanitizer (tests/tsan/)"
	@echo "make WERROR=0 ...  any target with warnings not turned into errors"
	@echo "make MPI=1 [test]  capdyn sweep under mpirun/srun too (build-mpi/; Open MPI: make mpi-deps)"
	@echo "make bench    benchmarks (bench/)"
	@echo "make fuzz     libFuzzer targets, FUZZ_SECONDS=N each (fuzz/fuzz.mk; installs clang)"
	@echo "make demo     install deps, run the Fig. 5 envelope grasp and render its figures"
	@echo "make figures  run the paper, gripper and capture scenarios, render every figure into figures/ (docs/figures.md)"
	@echo "make capture-map  the capture-success map (aim error x tumbling rate, ~25 runs; docs/capture.md)"
	@echo "make install PREFIX=/usr/local   static and shared libraries, headers, capdyn.pc, capdyn-io.pc, the CLI"
	@echo "make fmu      the FMU binary of capdyn fmu ($(BUILD)/fmu/linux64/; needs fmpy's FMI 2.0 headers in $(BUILD)/venv: make python-test)"
	@echo "make python-test  the Python package (python/) in $(BUILD)/venv, its pytest suite (docs/python.md)"
	@echo "make plots-test   every plot script on a user-written scenario (tests/plots/, docs/figures.md)"
	@echo "make gltf-test    capdyn export gltf against the Khronos glTF validator (npm, into $(BUILD)/npm)"
	@echo "make uninstall PREFIX=/usr/local removes exactly what install put there"

deps:
	@bash scripts/install-deps.sh
ifeq ($(MPI),1)
	@bash scripts/install-mpi-deps.sh
endif

mpi-deps:
	@bash scripts/install-mpi-deps.sh

check-deps:
	@CAPDYN_NO_INSTALL=1 bash scripts/install-deps.sh || { echo "run 'make deps' first (or 'make test' / 'make demo', which install them)" >&2; exit 1; }
ifeq ($(MPI),1)
	@CAPDYN_NO_INSTALL=1 bash scripts/install-mpi-deps.sh || { echo "MPI=1: run 'make mpi-deps' first (Open MPI)" >&2; exit 1; }
endif

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

# Examples: each examples/NAME.c is one self-contained program on the core
# library alone (<capdyn/capdyn.h>, libcapdyn.a, GSL, libccd), as an embedder
# builds it. Each is also a test: it exits non-zero when what it demonstrates
# does not hold.
$(BUILD)/examples/%: examples/%.c $(LIB)
	@mkdir -p $(dir $@)
	$(CC) -std=c99 $(WARN) $(OPT) -ffp-contract=off -Iinclude $(EXTRA_CFLAGS) -MMD -MP $(EXTRA_LDFLAGS) -o $@ $< $(LIB) $(LIBS_CORE)

# runs every example binary given; the first failure fails the target
run_examples = for e in $(1); do echo "$$e"; ./$$e || { echo "example $$e failed" >&2; exit 1; }; done

lib: $(LIB)
cli: $(CLI)
examples: check-deps $(EXAMPLES)

# ---- tests: make test (minutes), make test-long (the long physics) -------
# The one test command (README, .ci/run): installs what is missing, builds,
# runs every Criterion test but the long ones (Criterion prints its synthesis
# line; tests/run_tests.sh prints progress at least every 20 s), the
# failing-allocator test, every example (a failing example fails the
# target), the install check, then the doc tests (tests/doctest/run.sh:
# every shell block of README.md and docs/*.md, every C snippet of
# docs/embedding.md).
# TEST_LONG: the Criterion tests that take minutes (region sweeps, long
# gripper and capture runs; measured with tests/test_times.sh), run by
# `make test-long` (.ci/run runs it after make test). Moved, not removed.
TEST_LONG_LIST = \
  capture/body_offset_with_misalignment_is_captured \
  capture/detumbling_stops_the_held_target_at_the_grasp_limit \
  capture/squeezed_target_at_rest_does_not_drift \
  capture/checkpoint_with_the_controller_state_reruns_bit_identical \
  capture/too_fast_target_escapes \
  capture/handrail_tumbling_is_captured \
  capture/held_target_at_rest_does_not_drift \
  capture/momentum_is_conserved_through_the_space_grippers_clutch_events \
  capture/space_gripper_closes_on_the_trigger \
  capture/momentum_of_chaser_and_target_is_conserved \
  capture_scenarios/docking_fixture_is_captured \
  capture_scenarios/intermediate_axis_target_is_captured \
  capture_scenarios/solar_panels_target_is_not_reached \
  capture_scenarios/docking_fixture_conserves_momentum \
  gripper_scenarios/soft_gripper_wraps_with_every_link_in_contact \
  gripper_scenarios/space_gripper_cylinder_and_handrail_are_captured_with_one_clutch_per_finger \
  gripper_scenarios/tako_captures_near_the_palm_and_loses_beyond_the_fingertips \
  gripper/a_target_in_the_palm_frame_is_the_same_grasp_wherever_the_hand_is \
  gripper/verdicts_captured_escaped_unresolved \
  sweep/tako_vs_space_region_on_a_coarse_grid \
  sweep/a_small_cylinder_that_the_space_gripper_captures_and_tako_only_cages \
  mc/a_dispersed_duration_gives_the_analytic_capture_probability
tl_empty :=
tl_space := $(tl_empty) $(tl_empty)
TEST_LONG = @($(subst $(tl_space),|,$(strip $(TEST_LONG_LIST))))
TEST_ENV = CAPDYN_BIN=$(abspath $(CLI)) $(if $(filter 1,$(MPI)),CAPDYN_MPI_BIN=$(abspath $(CLI))) CAPDYN_ROOT=$(CURDIR)
test: deps
	@$(MAKE) --no-print-directory $(TESTBIN) $(CLI) $(EXAMPLES) $(FAILALLOC)
	@# the Python suite first: its venv (build/venv, with h5py) also serves the
	@# results-file kill tests, which read every dataset of a killed file with h5py
	@$(MAKE) --no-print-directory python-test
	@$(MAKE) --no-print-directory gltf-test plots-test
	$(TEST_ENV) bash tests/run_tests.sh $(TESTBIN) --jobs $(JOBS) --filter '!($(TEST_LONG))' $(TEST_ARGS)
	CAPDYN_ROOT=$(CURDIR) $(FAILALLOC)
	@$(call run_examples,$(EXAMPLES))
	@$(MAKE) --no-print-directory install-check
	@BUILD=$(BUILD) bash tests/doctest/run.sh

test-long: deps
	@$(MAKE) --no-print-directory $(TESTBIN) $(CLI)
	$(TEST_ENV) bash tests/run_tests.sh $(TESTBIN) --jobs $(JOBS) --filter '$(TEST_LONG)' $(TEST_ARGS)
	@BUILD=$(BUILD) DOCTEST_LONG=1 bash tests/doctest/run.sh

# the doc tests alone (after make)
doctest: check-deps $(LIB) $(CLI)
	@BUILD=$(BUILD) bash tests/doctest/run.sh
# ---- end of the test rules ----

# make asan runs the tests of make test under ASan + UBSan; the long physics
# regressions (TEST_LONG) run the same code paths over longer simulated
# times, at several times their cost under the sanitizers: ASAN_LONG=1 adds them
ASAN_FILTER = $(if $(filter 1,$(ASAN_LONG)),,--filter '!($(TEST_LONG))')
asan: deps
	@$(MAKE) --no-print-directory BUILD=build-asan OPT="-O1 -g -fno-omit-frame-pointer -fsanitize=address,undefined -fno-sanitize-recover=undefined" \
	  EXTRA_LDFLAGS="-fsanitize=address,undefined" build-asan/capdyn_tests build-asan/capdyn $(EXAMPLES:$(BUILD)/%=build-asan/%)
	CAPDYN_BIN=$(abspath build-asan/capdyn) CAPDYN_ROOT=$(CURDIR) ASAN_OPTIONS=detect_leaks=1 \
	  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  bash tests/run_tests.sh build-asan/capdyn_tests --jobs $(JOBS) $(ASAN_FILTER) $(TEST_ARGS)
	@export ASAN_OPTIONS=detect_leaks=1 LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 \
	  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1; $(call run_examples,$(EXAMPLES:$(BUILD)/%=build-asan/%))

# ThreadSanitizer (issue 24): the core library built with -fsanitize=thread
# and tests/tsan/two_threads.c, two threads on one shared model (a data
# each), which must end bit-identical to a run alone with no TSan report.
$(BUILD)/tsan_two_threads: tests/tsan/two_threads.c $(LIB)
	$(CC) -std=c99 $(WARN) $(OPT) -ffp-contract=off -Iinclude $(EXTRA_CFLAGS) -MMD -MP $(EXTRA_LDFLAGS) -pthread -o $@ $< $(LIB) $(LIBS_CORE)

tsan: deps
	@$(MAKE) --no-print-directory BUILD=build-tsan OPT="-O1 -g -fno-omit-frame-pointer -fsanitize=thread" \
	  EXTRA_LDFLAGS="-fsanitize=thread" build-tsan/tsan_two_threads
	TSAN_OPTIONS=halt_on_error=1 build-tsan/tsan_two_threads

-include bench/bench.mk
-include fuzz/fuzz.mk

# ---- install (docs/performance.md "Installing"; tests/install_check.sh) ----
# Static libraries, public headers, pkg-config files and the CLI under
# $(DESTDIR)$(PREFIX). Embedders link with `pkg-config --static --libs capdyn`
# (core) or `capdyn-io` (core + scenarios + HDF5).
PREFIX  ?= /usr/local
LIBDIR  ?= $(PREFIX)/lib
INCDIR  ?= $(PREFIX)/include
BINDIR  ?= $(PREFIX)/bin
PCDIR   ?= $(LIBDIR)/pkgconfig
VERSION := $(shell sed -n 's/^\#define CD_VERSION_STRING "\(.*\)"/\1/p' include/capdyn/model.h)
PUB_HEADERS = $(wildcard include/capdyn/*.h)
PC_FILES = capdyn.pc capdyn-io.pc
# installs into a temporary prefix, builds and runs the embedding programs
# against the installed copy only (add examples here as they come)
INSTALL_CHECK_SRC ?= tests/embed/embed_core.c tests/embed/embed_io.c $(EXAMPLE_SRC)

# ---- shared libraries (issue 19; docs/python.md "Shared libraries") ----
# The library objects are position-independent (-fPIC), so the same objects
# make the static archives (which can then go into a shared object too) and
# libcapdyn.so / libcapdyn_io.so. -fno-semantic-interposition keeps calls
# inside the library direct (no PLT, inlining as without -fPIC). Only the
# public API is exported: the cd_* functions declared in include/capdyn/*.h,
# listed at build time by scripts/public-symbols.sh into a linker version
# script (local: * hides every other symbol, internal cd_* ones and toml++'s
# C++ included); tests/install_check.sh compares `nm -D` with that list.
# soname: libcapdyn.so.MAJOR.MINOR while the major version is 0 (the ABI
# may change with every minor version), real name libcapdyn.so.VERSION.
PIC_FLAGS = -fPIC -fno-semantic-interposition
$(CORE_OBJ) $(IO_OBJ): CFLAGS_ALL += $(PIC_FLAGS)
$(CORE_OBJ) $(IO_OBJ): CXXFLAGS_ALL += $(PIC_FLAGS)
SOVERSION = $(word 1,$(subst ., ,$(VERSION))).$(word 2,$(subst ., ,$(VERSION)))
SO_MAP   = $(BUILD)/capdyn.map
SO       = $(BUILD)/libcapdyn.so
SO_IO    = $(BUILD)/libcapdyn_io.so
SO_REAL    = $(SO).$(VERSION)
SO_IO_REAL = $(SO_IO).$(VERSION)
SO_LDFLAGS = -shared -Wl,--no-undefined -Wl,--version-script=$(SO_MAP) $(EXTRA_LDFLAGS)

$(SO_MAP): $(PUB_HEADERS) scripts/public-symbols.sh
	@mkdir -p $(dir $@)
	CC="$(CC)" bash scripts/public-symbols.sh --version-script $(PUB_HEADERS) > $@.tmp && mv $@.tmp $@

$(SO_REAL): $(CORE_OBJ) $(SO_MAP)
	$(CC) $(OPT) $(SO_LDFLAGS) -Wl,-soname,$(notdir $(SO)).$(SOVERSION) -o $@ $(CORE_OBJ) $(LIBS_CORE)

$(SO_IO_REAL): $(IO_OBJ) $(SO_REAL) $(SO_MAP)
	$(CXX) $(OPT) $(SO_LDFLAGS) -Wl,-soname,$(notdir $(SO_IO)).$(SOVERSION) -o $@ $(IO_OBJ) $(SO_REAL) $(LIBS_IO) $(LIBS_CORE)

# the development and soname links next to each real file
$(SO) $(SO_IO): %.so: %.so.$(VERSION)
	ln -sf $(notdir $<) $*.so.$(SOVERSION)
	ln -sf $(notdir $*).so.$(SOVERSION) $@

shared: $(SO) $(SO_IO)

# The Python package (python/, docs/python.md): a virtual environment with
# the pinned PyPI packages of python/requirements.txt and the package built
# against these headers and shared libraries (scripts/install-python-deps.sh,
# Debian's python3-venv/python3-dev only when missing), then its pytest suite
# (pytest prints its closing line). PYTEST_ARGS adds pytest options.

# glTF export against the Khronos validator (npm gltf-validator, installed
# into $(BUILD)/npm; skipped without node/npm): tests/gltf/validate.sh
gltf-test: check-deps $(CLI)
	@BUILD=$(BUILD) CAPDYN=$(CLI) bash tests/gltf/validate.sh

# every plot script on a user-written scenario (tests/plots/run.sh)
plots-test: check-deps $(CLI)
	@BUILD=$(BUILD) CAPDYN=$(CLI) bash tests/plots/run.sh
VENV ?= $(BUILD)/venv
python-test: deps
	@$(MAKE) --no-print-directory $(CLI) $(SO) $(SO_IO)
	@BUILD=$(BUILD) VENV=$(VENV) bash scripts/install-python-deps.sh
	@$(MAKE) --no-print-directory fmu
	CAPDYN_BIN=$(abspath $(CLI)) CAPDYN_ROOT=$(CURDIR) CAPDYN_BUILD=$(abspath $(BUILD)) CC="$(CC)" \
	  $(VENV)/bin/pytest -p no:cacheprovider python/tests $(PYTEST_ARGS)

# ---- the FMU binary (issue 20; docs/fmu.md) ----
# The FMI 2.0 wrapper (src/fmu/) linked into one shared object with
# libcapdyn_io.a and libcapdyn.a (their objects are -fPIC), GSL linked
# statically (Debian's libgsl.a is position-independent), the other
# non-system libraries (libccd, toml++, Qhull: no static archive in Debian;
# GSL's CBLAS: Debian's libgslcblas.a is not -fPIC, so it cannot go into a
# shared object; HDF5 is not needed, --as-needed drops it) copied next to it by src/fmu/bundle.sh and found through the rpath
# $$ORIGIN. Only the fmi2* functions are exported (src/fmu/fmu.map). The FMI
# headers are fmpy's (BSD), taken from the venv at build time, never copied
# into the repository. capdyn fmu zips this directory into every FMU.
# (FMI2_HDR_DIR, FMU_DIR, FMU_SO, FMU_OBJ: defined at the top, for `all`)
$(BUILD)/fmu/obj/%.o: src/fmu/%.c
	@test -n "$(FMI2_HDR_DIR)" || { echo "FMU: no FMI 2.0 headers: fmpy is not installed in $(VENV) (make python-test installs it)" >&2; exit 1; }
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) $(PIC_FLAGS) -fvisibility=hidden -I$(FMI2_HDR_DIR) -MMD -MP -c $< -o $@
$(FMU_SO): $(FMU_OBJ) $(LIB_IO) $(LIB) src/fmu/fmu.map src/fmu/bundle.sh
	@mkdir -p $(dir $@)
	rm -f $(FMU_DIR)/*
	$(CXX) $(OPT) -shared -Wl,--no-undefined -Wl,--as-needed -Wl,--version-script=src/fmu/fmu.map -Wl,-rpath,'$$ORIGIN' $(EXTRA_LDFLAGS) \
	  -o $@ $(FMU_OBJ) $(LIB_IO) $(LIB) -Wl,-Bstatic -lgsl -Wl,-Bdynamic $(filter-out -lgsl,$(LIBS_IO) $(LIBS_CORE))
	bash src/fmu/bundle.sh $@
fmu: check-deps $(FMU_SO) $(CLI)
# capdyn fmu finds the binary here unless CAPDYN_FMU_DIR says otherwise
$(BUILD)/src/cli/fmu.o: CFLAGS_ALL += -DCAPDYN_FMU_DIR='"$(abspath $(FMU_DIR))"'

install: check-deps $(LIB) $(LIB_IO) $(CLI) $(SO) $(SO_IO)
	install -d $(DESTDIR)$(LIBDIR) $(DESTDIR)$(INCDIR)/capdyn $(DESTDIR)$(PCDIR) $(DESTDIR)$(BINDIR)
	install -m 644 $(LIB) $(LIB_IO) $(DESTDIR)$(LIBDIR)/
	install -m 755 $(SO_REAL) $(SO_IO_REAL) $(DESTDIR)$(LIBDIR)/
	for so in $(notdir $(SO) $(SO_IO)); do \
	  ln -sf $$so.$(VERSION) $(DESTDIR)$(LIBDIR)/$$so.$(SOVERSION) && ln -sf $$so.$(SOVERSION) $(DESTDIR)$(LIBDIR)/$$so || exit 1; \
	done
	install -m 644 $(PUB_HEADERS) $(DESTDIR)$(INCDIR)/capdyn/
	install -m 755 $(CLI) $(DESTDIR)$(BINDIR)/
	for pc in $(PC_FILES); do \
	  sed -e 's|@PREFIX@|$(PREFIX)|g' -e 's|@LIBDIR@|$(LIBDIR)|g' -e 's|@INCLUDEDIR@|$(INCDIR)|g' \
	      -e 's|@VERSION@|$(VERSION)|g' pkgconfig/$$pc.in > $(DESTDIR)$(PCDIR)/$$pc || exit 1; \
	done

uninstall:
	rm -f $(DESTDIR)$(LIBDIR)/$(notdir $(LIB)) $(DESTDIR)$(LIBDIR)/$(notdir $(LIB_IO))
	for so in $(notdir $(SO) $(SO_IO)); do rm -f $(DESTDIR)$(LIBDIR)/$$so $(DESTDIR)$(LIBDIR)/$$so.$(SOVERSION) $(DESTDIR)$(LIBDIR)/$$so.$(VERSION); done
	rm -f $(addprefix $(DESTDIR)$(INCDIR)/capdyn/,$(notdir $(PUB_HEADERS)))
	rm -f $(addprefix $(DESTDIR)$(PCDIR)/,$(PC_FILES)) $(DESTDIR)$(BINDIR)/$(notdir $(CLI))
	-rmdir $(DESTDIR)$(INCDIR)/capdyn 2>/dev/null

install-check: $(LIB) $(LIB_IO) $(CLI) $(SO) $(SO_IO)
	@BUILD=$(BUILD) MAKE="$(MAKE)" bash tests/install_check.sh $(INSTALL_CHECK_SRC)

demo: deps
	@$(MAKE) --no-print-directory $(CLI)
	@bash plots/demo.sh

figures: deps
	@$(MAKE) --no-print-directory $(CLI)
	@bash plots/figures.sh

capture-map: deps
	@$(MAKE) --no-print-directory $(CLI)
	@bash plots/capture_map.sh

clean:
	rm -rf build build-asan build-tsan build-fuzz build-mpi figures

-include $(CORE_OBJ:.o=.d) $(IO_OBJ:.o=.d) $(CLI_OBJ:.o=.d) $(FMU_OBJ:.o=.d) $(TEST_OBJ:.o=.d) $(EXAMPLES:=.d)
