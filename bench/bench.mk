# Benchmarks: `make bench`. Speed is judged here, never in unit tests.
BENCH_BIN = $(BUILD)/bench_core

$(BENCH_BIN): bench/bench_core.c $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -D_POSIX_C_SOURCE=199309L -o $@ $< $(LIB) $(LIBS_CORE)

bench: deps
	@$(MAKE) --no-print-directory $(BENCH_BIN) $(CLI)
	$(BENCH_BIN)
	@bash bench/bench_scenarios.sh
