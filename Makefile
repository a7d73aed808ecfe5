# Two commands a user needs (see README.md): `make demo` and `make test`.
# Both install missing Debian packages, create a catkin workspace that links
# to this checkout, and build there. The workspaces live outside the source
# tree (under $XDG_CACHE_HOME, one folder per checkout), so that nothing
# inside the package links back to it: rosrun then finds exactly one copy of
# each executable. `.build/setup.bash` sources the development workspace.

SHELL := /bin/bash
ROOT  := $(CURDIR)
CACHE ?= $(or $(XDG_CACHE_HOME),$(HOME)/.cache)/ekf_slam/$(shell printf %s '$(ROOT)' | md5sum | cut -c1-12)
WS    ?= $(CACHE)/ws
BENCH_WS ?= $(CACHE)/bench_ws
FUZZ_WS ?= $(CACHE)/fuzz_ws
SAN_WS ?= $(CACHE)/sanitize_ws
TSAN_WS ?= $(CACHE)/tsan_ws
FUZZ_SECONDS ?= 60
FUZZ_RUNS ?=
FUZZ_TARGETS ?=
export FUZZ_TARGETS
JOBS  ?= 2
OUT   ?= $(ROOT)/output
RVIZ  ?= 0

# Debian's ROS tools live in /usr/bin; a pyenv python3 earlier on PATH lacks
# the ROS modules.
export PATH := /usr/bin:/bin:/usr/sbin:/sbin:$(PATH)
CATKIN_ARGS := -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCATKIN_ENABLE_TESTING=ON

.PHONY: all deps workspace build test demo figures bench bench-workspace benchmark landmark-comparison line-experiment fuzz sanitize sanitize-thread format check clean

all: build

deps:
	@tools/ci/install_deps.sh

workspace:
	@for d in ws bench_ws; do if [ -d $(ROOT)/.build/$$d ]; then \
	  echo "make: removing .build/$$d (the workspaces now live in $(CACHE))"; rm -rf $(ROOT)/.build/$$d; fi; done
	@mkdir -p $(WS)/src $(ROOT)/.build
	@if [ ! -e $(WS)/src/ekf_slam ]; then ln -s $(ROOT) $(WS)/src/ekf_slam; fi
	@printf '# Sources the development workspace of this checkout (made by make).\nsource %s/devel/setup.bash\n' '$(WS)' > $(ROOT)/.build/setup.bash

build: deps workspace
	@cd $(WS) && catkin_make -j$(JOBS) $(CATKIN_ARGS) > $(WS)/build.log 2>&1 \
	  || { tail -n 60 $(WS)/build.log; echo "build failed; full log: $(WS)/build.log"; exit 1; }
	@echo "build: ok ($(WS))"

check:
	@tools/ci/check_core_ros_free.sh
	@tools/ci/check_layers.sh
	@tools/ci/check_format.sh
	@tools/ci/check_catkin_lint.sh
	@tools/ci/check_rosdep.sh

# The test programs are built here with -j$(JOBS): `catkin_make run_tests`
# (one job, so that the rostests never share the machine) would otherwise
# compile them one at a time.
test: build check
	@cd $(WS) && catkin_make -j$(JOBS) tests > $(WS)/build_tests.log 2>&1 \
	  || { tail -n 60 $(WS)/build_tests.log; echo "building the tests failed; full log: $(WS)/build_tests.log"; exit 1; }
	@tools/ci/run_tests.sh $(WS)

demo: build
	@source $(WS)/devel/setup.bash && RVIZ=$(RVIZ) tools/ci/run_demo.sh $(OUT)

# The thesis's Chapter 5 experiments redrawn: the loop closing on a
# simulated landmark world, the carton layout through the whole system, and
# the real logs offline; figures and figures.md in output/figures/.
figures: build
	@tools/dev/chapter5_figures.sh $(WS)/devel $(OUT)/figures

# The Release workspace (native code, benchmark tools) for the measurements
# on the real logs.
bench-workspace: deps
	@mkdir -p $(BENCH_WS)/src
	@if [ ! -e $(BENCH_WS)/src/ekf_slam ]; then ln -s $(ROOT) $(BENCH_WS)/src/ekf_slam; fi
	@cd $(BENCH_WS) && catkin_make -j$(JOBS) -DPYTHON_EXECUTABLE=/usr/bin/python3 \
	  -DCMAKE_BUILD_TYPE=Release -DEKF_SLAM_NATIVE=ON -DEKF_SLAM_BUILD_BENCH=ON -DCATKIN_ENABLE_TESTING=OFF > $(BENCH_WS)/build.log 2>&1 \
	  || { tail -n 60 $(BENCH_WS)/build.log; exit 1; }

bench: bench-workspace
	@mkdir -p $(OUT)/bench
	@tools/ci/run_benchmarks.sh $(BENCH_WS)/devel/lib/ekf_slam/bench $(OUT)/bench

# Offline SLAM on the real datasets in ../shared/datasets, scored with the
# relation metric; results in output/benchmark/ (summary.md).
benchmark: bench-workspace
	@tools/ci/run_dataset_benchmark.sh $(BENCH_WS)/devel $(OUT)/benchmark

# The landmark kinds (points, (p, θ) lines, θ-only lines) and the two
# association methods on every real log, with and without loop closure;
# tables in output/landmark_comparison/table.md (docs/results.md).
landmark-comparison: bench-workspace
	@tools/dev/landmark_comparison.sh $(BENCH_WS)/devel $(OUT)/landmark_comparison

# The thesis's line-feature simulation (§4.3.5): Monte Carlo runs of points
# only, points + (p, θ) lines and points + θ-only lines; text files and
# figures in output/line_experiment/.
line-experiment: deps
	@JOBS=$(JOBS) tools/dev/line_experiment.sh $(OUT)/line_experiment

# libFuzzer campaign: every fuzz target (or those in FUZZ_TARGETS),
# FUZZ_SECONDS each (FUZZ_RUNS inputs at most when set), clang with ASan +
# UBSan over everything linked. Corpus, reproducers and summary.md in
# output/fuzz/. The README's figures: make fuzz FUZZ_SECONDS=7200 FUZZ_RUNS=10000000
fuzz:
	@tools/ci/install_deps.sh clang
	@mkdir -p $(FUZZ_WS)/src $(OUT)/fuzz
	@if [ ! -e $(FUZZ_WS)/src/ekf_slam ]; then ln -s $(ROOT) $(FUZZ_WS)/src/ekf_slam; fi
	@cd $(FUZZ_WS) && catkin_make -j$(JOBS) -DPYTHON_EXECUTABLE=/usr/bin/python3 \
	  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DEKF_SLAM_FUZZ=ON \
	  -DCATKIN_ENABLE_TESTING=OFF ekf_slam_fuzzers > $(FUZZ_WS)/build.log 2>&1 \
	  || { tail -n 60 $(FUZZ_WS)/build.log; exit 1; }
	@tools/ci/run_fuzzers.sh $(FUZZ_WS)/devel/lib/ekf_slam/fuzz $(OUT)/fuzz $(FUZZ_SECONDS) $(FUZZ_RUNS)

# Every gtest under AddressSanitizer + UBSan (any report fails the test),
# with the executables the gtests run.
sanitize: deps
	@mkdir -p $(SAN_WS)/src
	@if [ ! -e $(SAN_WS)/src/ekf_slam ]; then ln -s $(ROOT) $(SAN_WS)/src/ekf_slam; fi
	@cd $(SAN_WS) && catkin_make -j$(JOBS) $(CATKIN_ARGS) -DEKF_SLAM_SANITIZE=ON tests ekf_slam_offline \
	  > $(SAN_WS)/build.log 2>&1 || { tail -n 60 $(SAN_WS)/build.log; exit 1; }
	@tools/ci/run_sanitized_tests.sh $(SAN_WS) $(OUT)/sanitize

# The gtests that run the back end on its own thread, under ThreadSanitizer
# (any report fails the run).
TSAN_TESTS := ekf_slam_core_loop_closure_test ekf_slam_core_pipeline_test
sanitize-thread: deps
	@mkdir -p $(TSAN_WS)/src
	@if [ ! -e $(TSAN_WS)/src/ekf_slam ]; then ln -s $(ROOT) $(TSAN_WS)/src/ekf_slam; fi
	@cd $(TSAN_WS) && catkin_make -j$(JOBS) $(CATKIN_ARGS) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DEKF_SLAM_SANITIZE_THREAD=ON $(TSAN_TESTS) > $(TSAN_WS)/build.log 2>&1 \
	  || { tail -n 60 $(TSAN_WS)/build.log; exit 1; }
	@for t in $(TSAN_TESTS); do \
	  TSAN_OPTIONS=halt_on_error=1 $(TSAN_WS)/devel/lib/ekf_slam/$$t > $(TSAN_WS)/$$t.log 2>&1 \
	    && echo "sanitize-thread: $$t passed, no report" \
	    || { tail -n 40 $(TSAN_WS)/$$t.log; echo "sanitize-thread: $$t FAILED"; exit 1; }; \
	done

format:
	@tools/ci/check_format.sh --fix

clean:
	rm -rf $(ROOT)/.build $(CACHE)
