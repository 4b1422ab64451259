# Benchmarks: `make bench`. Speed is judged here, never in unit tests.
# MuJoCo (Debian libmujoco-dev) is installed by the bench set-up only
# (scripts/install-bench-deps.sh); the library and `make test` never need it.
BENCH_BIN = $(BUILD)/bench_core
BENCH_SPEED = $(BUILD)/bench_speed
BENCH_REPS ?= 5
BENCH_HOLD ?= 10
BENCH_RESULT = bench/results/$(shell date -u +%Y-%m-%d).txt
BENCH_RESULT_AS_WRITTEN = bench/results/$(shell date -u +%Y-%m-%d)-rk8pd.txt
# capdyn's scenes run on the default stepper auto (docs/dynamics.md: rk8pd
# while not stiff, msbdf while stiff) with the step left to its error
# control, at rtol 1e-6 (the twins' own; the Fig. 5 grasp's file says 1e-8);
# a second pass runs them as their files are written (the Fig. 5 grasp: auto
# at rtol 1e-8, issue 18's target; the incline and capture twins: rk8pd)
BENCH_STIFF ?= simulation.integrator="auto";simulation.h_max=0.05;simulation.rtol=1e-6

$(BENCH_BIN): bench/bench_core.c bench/bench_chain.h $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -D_POSIX_C_SOURCE=199309L -o $@ $< $(LIB) $(LIBS_CORE)

# capdyn vs MuJoCo through both C APIs (bench/bench_speed.c, docs/performance.md)
$(BENCH_SPEED): bench/bench_speed.c bench/bench_chain.h bench/bench_util.h $(LIB_IO) $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -D_DEFAULT_SOURCE -c $< -o $@.o
	$(CXX) $(OPT) -o $@ $@.o $(LIB_IO) $(LIB) $(LIBS_IO) $(LIBS_CORE) -lmujoco

# every shipped scenario with its own settings; the broad phase on vs off
# (bench/bench_scenarios.c, docs/performance.md "Every scenario")
BENCH_SCEN = $(BUILD)/bench_scenarios
$(BENCH_SCEN): bench/bench_scenarios.c bench/bench_util.h $(LIB_IO) $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -D_POSIX_C_SOURCE=199309L -c $< -o $@.o
	$(CXX) $(OPT) -o $@ $@.o $(LIB_IO) $(LIB) $(LIBS_IO) $(LIBS_CORE)

# tick times of a control loop per stepper (bench/bench_ticks.c; it counts
# heap allocations by interposing malloc, so it is linked without sanitizers)
BENCH_TICKS = $(BUILD)/bench_ticks
$(BENCH_TICKS): bench/bench_ticks.c bench/bench_util.h examples/control_loop_model.h $(LIB_IO) $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -D_POSIX_C_SOURCE=199309L -c $< -o $@.o
	$(CXX) $(OPT) -o $@ $@.o $(LIB_IO) $(LIB) $(LIBS_IO) $(LIBS_CORE)

# the stiffest modes of a scenario's state at a time of its run (a
# diagnostic for what caps an explicit step: bench/stiff_modes.c)
BENCH_MODES = $(BUILD)/stiff_modes
$(BENCH_MODES): bench/stiff_modes.c $(LIB_IO) $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -c $< -o $@.o
	$(CXX) $(OPT) -o $@ $@.o $(LIB_IO) $(LIB) $(LIBS_IO) $(LIBS_CORE)

# the cost of driving a scenario by cd_sim_advance in ticks of DT
# (bench/advance_ticks.c; docs/dynamics.md "auto", short advance calls)
BENCH_ADVANCE = $(BUILD)/advance_ticks
$(BENCH_ADVANCE): bench/advance_ticks.c $(LIB_IO) $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -c $< -o $@.o
	$(CXX) $(OPT) -o $@ $@.o $(LIB_IO) $(LIB) $(LIBS_IO) $(LIBS_CORE)

bench-deps: deps
	@bash scripts/install-bench-deps.sh

BENCH_DAY = bench/results/$(shell date -u +%Y-%m-%d)
BENCH_SCEN_CAP ?= 30
bench: bench-deps
	@$(MAKE) --no-print-directory $(BENCH_BIN) $(BENCH_SPEED) $(BENCH_SCEN) $(BENCH_TICKS) $(CLI)
	@mkdir -p bench/results
	$(BENCH_BIN)
	$(BENCH_SCEN) -r 1 --cap $(BENCH_SCEN_CAP) -o $(BENCH_DAY)-scenarios.txt scenarios/*.toml
	$(BENCH_SCEN) --ab-broad-phase -r 3 --cap 120 -o $(BENCH_DAY)-broadphase.txt bench/capture_twin.toml scenarios/capture_handrail_tumbling.toml scenarios/capture_too_fast.toml
	$(BENCH_TICKS) -o $(BENCH_DAY)-ticks.txt
	CAPDYN_BENCH_SET='$(BENCH_STIFF)' $(BENCH_SPEED) -r $(BENCH_REPS) --hold $(BENCH_HOLD) -o $(BENCH_RESULT)
	CAPDYN_BENCH_SET= $(BENCH_SPEED) -r $(BENCH_REPS) --hold $(BENCH_HOLD) --scenes-only -o $(BENCH_RESULT_AS_WRITTEN)
	@echo "results: $(BENCH_DAY)-scenarios.txt (every scenario), $(BENCH_DAY)-broadphase.txt (broad phase on/off),"
	@echo "         $(BENCH_DAY)-ticks.txt (control-loop ticks), $(BENCH_RESULT) (vs MuJoCo, capdyn with auto),"
	@echo "         $(BENCH_RESULT_AS_WRITTEN) (vs MuJoCo, the scenes as written)"

.PHONY: bench-deps

# grasp quality: cone linearisation error and Qhull cost vs cone edges
# (docs/grasp-quality.md); needs only the io library and Qhull
BENCH_GRASP = $(BUILD)/bench_grasp_quality
$(BENCH_GRASP): bench/bench_grasp_quality.c $(LIB_IO) $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -o $@ $< $(LIB_IO) $(LIB) $(LIBS_IO) $(LIBS_CORE)

bench-grasp: deps
	@$(MAKE) --no-print-directory $(BENCH_GRASP)
	$(BENCH_GRASP)

.PHONY: bench-grasp
