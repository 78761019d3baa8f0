# SPDX-License-Identifier: MIT
# The two commands of the quick start, `make demo` and `make test`, and the benchmarks. Each
# installs what is missing, configures a Release build in build/ and builds it.
BUILD ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=

.PHONY: all deps configure build demo test bench bench-torch bench-nerf clean

all: build

deps:
	@bash scripts/install_deps.sh

$(BUILD)/CMakeCache.txt: | deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null

configure: deps $(BUILD)/CMakeCache.txt

build: configure
	@cmake --build $(BUILD) -j $(JOBS)

demo: build
	@bash scripts/demo.sh $(BUILD)

test: build
	@cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

bench: build
	@$(BUILD)/bin/nfield bench

bench-torch: build
	@NFIELD_WITH_TORCH=1 bash scripts/install_deps.sh
	@bash bench/compare_torch.sh $(BUILD)

bench-nerf: build
	@NFIELD_WITH_TORCH=1 bash scripts/install_deps.sh
	@bash bench/compare_nerf.sh $(BUILD)

clean:
	@rm -rf $(BUILD)
