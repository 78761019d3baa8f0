# SPDX-License-Identifier: MIT
# The two commands of the quick start: `make demo` and `make test`. Both install what is
# missing, configure a Release build in build/ and build it.
BUILD ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=

.PHONY: all deps configure build demo test bench bench-torch clean

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

clean:
	@rm -rf $(BUILD)
