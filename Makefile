# hgrasp: `make run` and `make test` take a fresh Debian 12 machine from clone to result.
# deps   installs the Debian packages that are missing (idempotent; sudo only when not root)
# build  configures and builds (Release) in build/
# run    builds, then runs the whole grasp (hgrasp run) on the default scenario headless into
#        out/default/
# twin   builds, then starts `hgrasp twin` on scenarios/twin_robot.yaml (every device on its real
#        wire, in wall-clock time) and runs the whole grasp against it through the real drivers
#        into out/twin/; the twin's account (frames, overruns, truth) in $(TWIN_DIR)/twin.json
# test   builds, then runs every test: the simulated-time ones two at a time (ctest -LE realtime),
#        then the wall-clock ones (label realtime: ptys, streams, the twin's wires) alone
# bench  builds, then runs the benchmarks in tests/bench/
# fuzz   builds the protocol decoders' and the file loaders' libFuzzer targets with clang (ASan + UBSan) in build-fuzz/
#        and runs each for FUZZ_RUNS inputs

JOBS     ?= 2
BUILD    ?= build
SCENARIO ?= scenarios/default.yaml
OUT      ?= out/default
TWIN_DIR ?= /tmp/hgrasp-twin
FUZZ_BUILD ?= build-fuzz
FUZZ_RUNS  ?= 1000000
FUZZERS    := val2_fuzz biclops_fuzz sensorhand_fuzz laser_board_fuzz loaders_fuzz

PACKAGES := build-essential cmake pkg-config git \
	libmujoco-dev libeigen3-dev libopencv-dev liburdfdom-dev liburdfdom-tools \
	libyaml-cpp-dev libcli11-dev libspdlog-dev nlohmann-json3-dev \
	libegl-dev libgl-dev libopengl-dev libegl-mesa0 libgl1-mesa-dri \
	libgtest-dev libgmock-dev libbenchmark-dev \
	gstreamer1.0-plugins-base gstreamer1.0-plugins-bad gstreamer1.0-tools \
	libgstreamer1.0-dev libgstreamer-plugins-base1.0-dev libmujoco-samples \
	slurm-wlm munge chromium python3-junitparser

SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: deps build run twin test bench fuzz clean

deps:
	@missing=$$(for p in $(PACKAGES); do \
	  dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q '^install ok installed' || echo $$p; \
	done); \
	if [ -n "$$missing" ]; then \
	  echo "installing:" $$missing; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing; \
	else echo "deps: all packages present"; fi

$(BUILD)/CMakeCache.txt:
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release

build: deps $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j$(JOBS)

run: build
	./$(BUILD)/hgrasp run $(SCENARIO) --out $(OUT)
	@echo "make run: $(OUT)/servo_*.png (tracked and target hand at key moments), left.avi (the left camera), grasp.png, models.png, segments.png, range.png, models.obj, report.json"

twin: build
	@rm -f $(TWIN_DIR)/ready; \
	./$(BUILD)/hgrasp twin scenarios/twin_robot.yaml --dir $(TWIN_DIR) & twin=$$!; \
	for i in $$(seq 600); do [ -e $(TWIN_DIR)/ready ] && break; sleep 0.1; done; \
	./$(BUILD)/hgrasp run scenarios/twin_robot.yaml --out out/twin; status=$$?; \
	kill -INT $$twin; wait $$twin; \
	echo "make twin: out/twin/ (the run through the real drivers), $(TWIN_DIR)/twin.json (the twin: frames, overruns, truth, command logs), $(TWIN_DIR)/world.xml (mujoco-simulate opens it)"; \
	exit $$status

test: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS) -LE realtime; status=$$?; \
	ctest --output-on-failure -j1 -L realtime && exit $$status

bench: build
	./$(BUILD)/tests/bench/hgrasp_bench --benchmark_counters_tabular=true

fuzz: deps
	@missing=; for p in clang libclang-rt-dev; do \
	  dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q '^install ok installed' || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing; fi
	CC=clang CXX=clang++ cmake -S . -B $(FUZZ_BUILD) -DHGRASP_FUZZ=ON -DHGRASP_BUILD_TESTS=OFF \
	  -DCMAKE_BUILD_TYPE=RelWithDebInfo
	cmake --build $(FUZZ_BUILD) -j$(JOBS) --target $(FUZZERS)
	@# The loaders' fuzzer starts from every shipped and test file, its first byte naming the loader
	@# (0 scenario, 1 cameras, 2 laser, 3 LEDs), and takes inputs up to 4 kB.
	@corpus=$(FUZZ_BUILD)/corpus/loaders; rm -rf $$corpus; mkdir -p $$corpus; i=0; \
	for f in scenarios/*.yaml tests/data/scenarios/*.yaml; do { printf '\000'; cat $$f; } > $$corpus/s$$i; i=$$((i+1)); done; \
	for f in calibration/sim/cameras.yaml tests/data/calibration/bad_cameras_*.yaml; do { printf '\001'; cat $$f; } > $$corpus/c$$i; i=$$((i+1)); done; \
	for f in calibration/sim/laser.yaml tests/data/calibration/bad_laser_*.yaml; do { printf '\002'; cat $$f; } > $$corpus/l$$i; i=$$((i+1)); done; \
	{ printf '\003'; cat calibration/sim/leds.yaml; } > $$corpus/led
	@for f in $(FUZZERS); do \
	  echo "== $$f: $(FUZZ_RUNS) inputs"; \
	  if [ $$f = loaders_fuzz ]; then args="-max_len=4096 -timeout=10 $(FUZZ_BUILD)/corpus/loaders"; \
	  else args="-max_len=512"; fi; \
	  ./$(FUZZ_BUILD)/tests/fuzz/$$f -runs=$(FUZZ_RUNS) -print_final_stats=1 $$args || exit 1; \
	done

clean:
	rm -rf $(BUILD) $(FUZZ_BUILD) out
