# hooke: the two entry points are `make demo` and `make test`; both install missing Debian
# packages first (scripts/install-deps.sh), then configure and build Release in build/.
BUILD ?= build
JOBS ?= 2
CMAKE_FLAGS ?=
# make fuzz: how long the libFuzzer run lasts (seconds).
FUZZ_SECONDS ?= 600
# make sanitize: CTest tiers (labels, see tests/CMakeLists.txt) left out under ASan/UBSan:
# install (its consumer project is not built with the sanitizer flags), accuracy (the reference
# studies that take 20 s to 6 min each under ASan: agreement with CVODE, Ceres against Newton,
# every backend on the same cloth step, Gauss-Seidel convergence, crosscheck; together 20 minutes
# of the 25 on 2 cores) and perf-target (the 256 x 256 and 411 x 411 target cloths, 10-16 s each
# in Release). Their code paths stay covered by the unit tests of the same backends.
# fast_unwind_on_malloc=0: full stacks for allocations inside Open MPI's plugins (loaded by the
# PETSc backend), which tests/sanitizer/lsan.supp can then name.
SANITIZE_LABELS_EXCLUDE ?= accuracy|perf-target|install

.PHONY: all deps configure build demo test paper sanitize fuzz format check-format clean

all: build

deps:
	bash scripts/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS)

build: configure
	cmake --build $(BUILD) -j $(JOBS)

# The demo (`hooke demo`, experiments/demo_command.cpp): the stiff cloth by backward Euler at a
# step where symplectic Euler diverges, both run -> out/demo/{demo.png,summary.txt,implicit/,explicit/}
# (each run folder holds log.csv, final.csv, frames/ and final.png).
demo: configure
	cmake --build $(BUILD) -j $(JOBS) --target hooke
	$(BUILD)/bin/hooke demo --out out/demo
	@echo "demo: picture out/demo/demo.png, summary out/demo/summary.txt, data out/demo/implicit/ and out/demo/explicit/"

# The paper: runs `hooke stability`, `hooke workprecision` and `hooke resolution` at their default
# (small) size into out/paper/ and renders out/paper/paper.html from paper/paper.md with pandoc.
# `make paper FULL=1` runs them at the paper's size (--full; much longer).
paper: configure
	bash scripts/install-deps.sh --paper
	cmake --build $(BUILD) -j $(JOBS) --target hooke
	bash paper/build.sh $(BUILD)/bin/hooke out/paper$(if $(FULL),-full) $(if $(FULL),--full)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# The unit, cli, reliability and malformed tiers under AddressSanitizer and
# UndefinedBehaviorSanitizer (GCC, RelWithDebInfo) in build-asan/ (preset "asan").
sanitize: deps
	cmake --preset asan $(CMAKE_FLAGS)
	cmake --build build-asan -j $(JOBS)
	cd build-asan && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:fast_unwind_on_malloc=0 \
	  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/sanitizer/lsan.supp:print_suppressions=0 \
	  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --output-on-failure -j $(JOBS) -LE '^($(SANITIZE_LABELS_EXCLUDE))$$'

# libFuzzer on the scene loader (clang-14, ASan + UBSan) in build-fuzz/ (preset "fuzz"). New
# interesting inputs go to build-fuzz/corpus; crashes to build-fuzz/crash-*. FUZZ_SECONDS=600.
fuzz:
	bash scripts/install-deps.sh fuzz
	cmake --preset fuzz $(CMAKE_FLAGS)
	cmake --build build-fuzz -j $(JOBS) --target hooke_scene_fuzz
	mkdir -p build-fuzz/corpus
	cd build-fuzz && ./bin/hooke_scene_fuzz -max_total_time=$(FUZZ_SECONDS) -timeout=30 \
	  -print_final_stats=1 -artifact_prefix=$(CURDIR)/build-fuzz/ corpus \
	  $(CURDIR)/problems/scenes $(CURDIR)/tests/problems/malformed

# clang-format every C++ source in place (.clang-format); check-format only lists the unformatted.
format:
	bash scripts/install-deps.sh format
	git ls-files --cached --others --exclude-standard '*.cpp' '*.hpp' '*.inc' | \
	  grep -v '^tests/problems/malformed/' | xargs clang-format -i

check-format:
	bash scripts/check-format.sh

clean:
	rm -rf $(BUILD) build-asan build-fuzz out
