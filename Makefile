# fpgacnc top-level Makefile: thin wrapper over CMake/CTest.
BUILD ?= build
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
# Build jobs (one more than the cores was measured: no faster on 2 cores, more CPU time).
BUILD_JOBS ?= $(JOBS)
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release
DEMO_JOB ?= examples/jsdc-laser.gcode
DEMO_ARGS ?= --plot $(BUILD)/demo-path.svg
# The Verilated half of the demo: the first DEMO_RTL_MOVES moves, 25 times faster than written
# (examples/demo-machine.toml), through the pty into both boards, compared.
DEMO_RTL_MOVES ?= 100
DEMO_RTL_ARGS ?= --config examples/demo-machine.toml

.PHONY: all deps configure build test lint bench demo synth synth-budget quartus formal format clean spec

all: build

# Install the Debian packages that are missing (a no-op when all are present).
deps:
	@./scripts/install-deps.sh

# CMake's Ninja generator when ninja is there (scripts/install-deps.sh installs it): it compiles a
# target's sources as soon as the headers they need exist, not after every library the target
# links, and has no per-target dependency scan: a fresh build took 4 min 48 s instead of 5 min 12 s
# on 2 cores. A build folder keeps the generator it was configured with.
configure: deps
	@if [ ! -f $(BUILD)/CMakeCache.txt ]; then \
	  gen=""; if command -v ninja >/dev/null 2>&1; then gen="-G Ninja"; fi; \
	  cmake -S . -B $(BUILD) $$gen $(CMAKE_FLAGS); fi

# An RTL edit re-runs Verilator while CMake configures (fpgacnc_verilate() in CMakeLists.txt), so
# a build compiles the models' current file lists the first time.
build: configure
	cmake --build $(BUILD) -j $(BUILD_JOBS)

# Regenerate the files written from spec/protocol.toml and spec/configs.toml (Verilog and C++
# headers, spec.cmake, the worked-frame vectors, the configurations for CMake and the scripts, the
# docs' tables); the CTest spec_generated_up_to_date checks them.
spec:
	python3 scripts/gen_spec.py

# The grbl label (the front end and the real CNCjs against the twin board) waits mostly on its
# pty and on CNCjs's wall-clock polling, not on the CPU: it runs one test at a time beside the
# CPU-bound tests instead of taking one of their JOBS slots; its output follows theirs.
test: build
	cd $(BUILD) && { ctest --output-on-failure -L grbl -j 1 --timeout 1200 > grbl-tests.log 2>&1 & \
	  g=$$!; ctest --output-on-failure -LE grbl -j $(JOBS) --timeout 1200; r=$$?; \
	  wait $$g; gr=$$?; echo "--- label grbl (ran beside the others):"; cat grbl-tests.log; \
	  test $$r -eq 0 && test $$gr -eq 0; }

# RTL/twin co-simulation soak: many more random seeds and longer corpus prefixes at real feeds
# (SOAK_SEEDS, SOAK_SEED, SOAK_MOVES; about 2 minutes per 20 seeds of 100 segments).
SOAK_SEEDS ?= 200
SOAK_SEED ?= 1000
SOAK_MOVES ?= 60
.PHONY: soak
soak: build
	$(BUILD)/systemc/cosim --seed $(SOAK_SEED) --seeds $(SOAK_SEEDS) --segments 100 --corpus-moves $(SOAK_MOVES) --corpus-feed-override 100
	$(BUILD)/systemc/cosim_executor --seed $(SOAK_SEED) --seeds $(SOAK_SEEDS) --segments 100
	$(BUILD)/systemc/cosim_blocks --seed $(SOAK_SEED) --seeds $(SOAK_SEEDS)
	$(BUILD)/systemc/cosim_heater --seed $(SOAK_SEED) --seeds 20 --seconds 3600
	$(BUILD)/systemc/arc_twin_rtl --seed $(SOAK_SEED) --arcs 20000
	FPGACNC_V2_SEGMENTS=10000 $(BUILD)/host/simboard/simboard_v2_system_tests --gtest_filter='*ZeroGap*'
	FPGACNC_V2_FAULT_SEGMENTS=2000 $(BUILD)/host/simboard/simboard_v2_system_tests --gtest_filter='*LineFaults*'
	FPGACNC_EXEC_BATCHES=400 $(BUILD)/tb/test_segment_executor --gtest_filter='*RandomSegmentsExactTiming*'
	FPGACNC_PROFILE_STREAMS=400 $(BUILD)/tb/test_profile --gtest_filter='*RandomSegmentsEdgeForEdge*'
	$(BUILD)/host/simboard/simboard_tests --gtest_filter='SimBoardCorpus.*'
	$(BUILD)/systemc/corpus_files_tests
	$(BUILD)/host/fpgacnc sim examples/jsdc-laser.gcode --model both --protocol v1 --config examples/demo-machine.toml
	$(BUILD)/host/fpgacnc sim $(CORPUS)/Circle_Diamond_Square_Calibration.gcode --model both --protocol v1 --config systemc/cosim/corpus-fast-mill.toml
	$(BUILD)/host/fpgacnc sim examples/jsdc-laser.gcode --model both --protocol v2 --config systemc/cosim/jsdc-constant.toml
	$(BUILD)/host/fpgacnc sim examples/jsdc-laser.gcode --model both --protocol v2 --config systemc/cosim/jsdc-profile.toml
	$(MAKE) fuzz-soak
	$(MAKE) soak-part-heaters

# part.gcode end to end on the simulated board with heaters: printer start sequence
# (M140/M104/M190/M109), the whole file (44 305 lines), heaters off; hours of simulation (the
# motion runs in real board time at 50 MHz).
CORPUS ?= corpus/cncjs
.PHONY: soak-part-heaters heater-plot
soak-part-heaters: build
	cat examples/printer-start.gcode $(CORPUS)/part.gcode examples/printer-end.gcode > $(BUILD)/part-heaters.gcode
	$(BUILD)/host/fpgacnc stream $(BUILD)/part-heaters.gcode --heater-plot $(BUILD)/part-heaters.svg

# The bed warm-up plot of docs/heater.md (temperature, setpoint and duty from STATUS, plant time).
heater-plot: build
	$(BUILD)/host/fpgacnc stream examples/bed-warmup.gcode --config examples/bed-warmup.toml --heater-plot docs/images/bed-warmup.svg

# libFuzzer targets (clang, ASan + UBSan; separate tree $(BUILD)/fuzz): `make fuzz` (a step of
# .ci/run) runs each FUZZ_TIME seconds from a fresh working corpus, `make fuzz-soak`
# FUZZ_SOAK_TIME seconds each, keeping the working corpus between runs. `make test` replays the
# seed corpora through gcc builds of the same targets (CTest fuzz_replay_*), without libFuzzer.
FUZZ_TIME ?= 30
FUZZ_SOAK_TIME ?= 600
FUZZ_SEED ?= 1
.PHONY: fuzz fuzz-soak
fuzz: deps
	./scripts/fuzz.sh smoke --time $(FUZZ_TIME) --seed $(FUZZ_SEED) --build-dir $(BUILD)/fuzz
fuzz-soak: deps
	./scripts/fuzz.sh soak --time $(FUZZ_SOAK_TIME) --seed $(FUZZ_SEED) --build-dir $(BUILD)/fuzz

lint: deps
	./scripts/lint.sh

bench: build
	cmake --build $(BUILD) -j $(JOBS) --target bench_protocol
	./scripts/bench.sh $(BUILD)

# The whole job at its real feeds through the pty into the twin board (--model tlm, the default),
# then its first moves into the Verilated board and the twin board, compared (fails on any
# difference). Builds only the fpgacnc command.
demo: configure
	cmake --build $(BUILD) -j $(JOBS) --target fpgacnc
	$(BUILD)/host/fpgacnc stream $(DEMO_JOB) $(DEMO_ARGS)
	$(BUILD)/host/fpgacnc stream $(DEMO_JOB) --model both --max-moves $(DEMO_RTL_MOVES) $(DEMO_RTL_ARGS)

# Open-tool synthesis: Cyclone V resource report against the budget, iCE40 place and route at 50 MHz;
# every block of the full design must meet 50 MHz alone on the iCE40 on each seed of SYNTH_SEEDS.
SYNTH_SEEDS ?= 1 2 3
# The Cyclone V resources of the original controller's feature set (v1-board) and of the DE1-SoC
# board (full-2axis, de1soc_top) against their budgets; fails on a Yosys warning too. About 4
# CPU-minutes of Yosys, so a step of its own (CI runs it after `make formal`) rather than a CTest.
synth-budget: deps
	CONFIGS="v1-board full-2axis" SYNTH_NAMES=0 ./scripts/synth_report.sh $(BUILD)/synth-budget

synth: deps
	EXTRA=v1-board-fixed ./scripts/synth_report.sh $(BUILD)/synth
	./scripts/ice40_timing.sh $(BUILD)/synth
	STRICT=1 SEEDS="$(SYNTH_SEEDS)" ./scripts/ice40_blocks.sh $(BUILD)/synth

# Formal proofs of the `ifdef FORMAL` properties (Yosys + yosys-smtbmc + Z3); prints a table.
# A separate step from `make test` (about 2-3 minutes on 2 cores).
formal: deps
	./scripts/formal.sh $(BUILD)/formal

# Quartus compile and timing report (needs quartus_sh on the PATH; says what is missing otherwise).
quartus:
	./scripts/quartus.sh

format:
	find models host tb systemc -name '*.cpp' -o -name '*.h' -o -name '*.hpp' | xargs clang-format -i

clean:
	rm -rf $(BUILD)
