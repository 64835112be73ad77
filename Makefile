# hooke: the two entry points are `make demo` and `make test`; both install missing Debian
# packages first (scripts/install-deps.sh), then configure and build Release in build/.
BUILD ?= build
JOBS ?= 2
CMAKE_FLAGS ?=

.PHONY: all deps configure build demo test paper clean

all: build

deps:
	bash scripts/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS)

build: configure
	cmake --build $(BUILD) -j $(JOBS)

# The default scene: a cloth hanging from two corners -> out/demo/{final.png,log.csv,final.csv,frames/}
demo: configure
	cmake --build $(BUILD) -j $(JOBS) --target hooke
	$(BUILD)/bin/hooke run problems/scenes/hanging_cloth.toml --out out/demo
	@echo "demo: picture out/demo/final.png, data out/demo/log.csv and out/demo/final.csv, frames out/demo/frames.pvd"

# The paper: runs `hooke stability`, `hooke workprecision` and `hooke resolution` at their default
# (small) size into out/paper/ and renders out/paper/paper.html from paper/paper.md with pandoc.
# `make paper FULL=1` runs them at the paper's size (--full; much longer).
paper: configure
	bash scripts/install-deps.sh --paper
	cmake --build $(BUILD) -j $(JOBS) --target hooke
	bash paper/build.sh $(BUILD)/bin/hooke out/paper$(if $(FULL),-full) $(if $(FULL),--full)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

clean:
	rm -rf $(BUILD) out
