# libFuzzer targets (docs/reliability.md "## Input"), included by the Makefile.
#   make fuzz FUZZ_SECONDS=N   install clang + libFuzzer (scripts/install-fuzz-deps.sh),
#                              build, run each target N seconds (default 60)
# Targets: fuzz_loader (cd_scenario_load with overrides) and fuzz_model (load,
# cd_data_create, a short run), both on a 256 KiB-stack thread, built with
# clang -fsanitize=fuzzer,address,undefined into build-fuzz/. The seed corpus
# is every .toml of scenarios/, tests/data/scenarios/ and tests/bad_inputs/;
# what the fuzzer adds stays in build-fuzz/corpus_<target>/. A finding stops
# the target, leaves its input in build-fuzz/ (crash-*, leak-*, timeout-*) and
# fails the make.

FUZZ_SECONDS ?= 60
FUZZ_BUILD   = build-fuzz
FUZZ_CC      = clang
FUZZ_CXX     = clang++
FUZZ_SAN     = -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined
FUZZ_OPT     = -O1 -g -fno-omit-frame-pointer $(FUZZ_SAN)
FUZZ_CFLAGS  = -std=c99 $(WARN) $(FUZZ_OPT) -ffp-contract=off -Iinclude $(shell pkg-config --cflags $(PKGS_CORE) $(PKGS_IO) 2>/dev/null)
FUZZ_CXXFLAGS = -std=c++17 $(WARN) $(FUZZ_OPT) -ffp-contract=off -Iinclude $(shell pkg-config --cflags $(PKGS_CORE) $(PKGS_IO) 2>/dev/null)
FUZZ_LIB_SRC = $(CORE_SRC) $(IO_SRC_C)
FUZZ_LIB_OBJ = $(FUZZ_LIB_SRC:%.c=$(FUZZ_BUILD)/%.o) $(IO_SRC_CXX:%.cpp=$(FUZZ_BUILD)/%.o)
FUZZ_TARGETS = fuzz_loader fuzz_model
FUZZ_BINS    = $(FUZZ_TARGETS:%=$(FUZZ_BUILD)/%)
# libFuzzer options: inputs up to 64 KiB, 10 s per input, 2 GiB of memory
FUZZ_RUN_OPTS = -max_len=65536 -timeout=10 -rss_limit_mb=2048 -dict=fuzz/scenario.dict -print_final_stats=1

.PHONY: fuzz fuzz-deps fuzz-build

fuzz-deps:
	@bash scripts/install-fuzz-deps.sh

$(FUZZ_BUILD)/%.o: %.c
	@mkdir -p $(dir $@)
	$(FUZZ_CC) $(FUZZ_CFLAGS) -MMD -MP -c $< -o $@

$(FUZZ_BUILD)/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(FUZZ_CXX) $(FUZZ_CXXFLAGS) -MMD -MP -c $< -o $@

$(FUZZ_BUILD)/fuzz/%.o: fuzz/%.c fuzz/fuzz_common.h
	@mkdir -p $(dir $@)
	$(FUZZ_CC) $(FUZZ_CFLAGS) -D_POSIX_C_SOURCE=200809L -MMD -MP -c $< -o $@

$(FUZZ_BUILD)/fuzz_%: $(FUZZ_BUILD)/fuzz/fuzz_%.o $(FUZZ_LIB_OBJ)
	$(FUZZ_CXX) -fsanitize=fuzzer,address,undefined -o $@ $^ $(LIBS_IO) $(LIBS_CORE) -lpthread

$(FUZZ_BUILD)/seeds: $(wildcard scenarios/*.toml tests/data/scenarios/*.toml tests/bad_inputs/*.toml)
	@rm -rf $@ && mkdir -p $@
	@cp $^ $@/

fuzz-build: fuzz-deps
	@$(MAKE) --no-print-directory $(FUZZ_BINS) $(FUZZ_BUILD)/seeds

# Each target in turn, FUZZ_SECONDS each, in build-fuzz/ (findings land there).
# The seeds' includes are resolved next to the temporary scenario file, so
# they mostly fail to load: the fuzzer mutates them into what loads.
fuzz: fuzz-build
	@set -e; for t in $(FUZZ_TARGETS); do \
	  mkdir -p $(FUZZ_BUILD)/corpus_$$t; \
	  echo "fuzz: $$t for $(FUZZ_SECONDS) s (log: $(FUZZ_BUILD)/$$t.log)"; \
	  if ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1 UBSAN_OPTIONS=print_stacktrace=1 \
	    $(FUZZ_BUILD)/$$t $(FUZZ_RUN_OPTS) -max_total_time=$(FUZZ_SECONDS) -artifact_prefix=$(FUZZ_BUILD)/$$t- \
	    $(FUZZ_BUILD)/corpus_$$t $(FUZZ_BUILD)/seeds > $(FUZZ_BUILD)/$$t.log 2>&1; then \
	    grep -E '^#[0-9]+ *DONE|stat::number_of_executed_units|stat::new_units_added' $(FUZZ_BUILD)/$$t.log || true; \
	  else \
	    tail -40 $(FUZZ_BUILD)/$$t.log >&2; \
	    echo "fuzz: $$t found a problem (or could not run): see $(FUZZ_BUILD)/$$t.log" >&2; exit 1; \
	  fi; \
	done

.SECONDARY: $(FUZZ_LIB_OBJ) $(FUZZ_TARGETS:%=$(FUZZ_BUILD)/fuzz/%.o)

-include $(FUZZ_LIB_OBJ:.o=.d)
