# SPDX-License-Identifier: MIT
# The two commands of the quick start, `make demo` and `make test`, and the benchmarks. Each
# installs what is missing, configures a Release build in build/ and builds it.
BUILD ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=

# test-sanitize: the tests labelled `sanitize` (some of every folder) in a separate build
# under AddressSanitizer and UBSan, at -O1 and without MPI, Python, benchmarks or examples.
SANITIZE ?= address,undefined
SANITIZE_BUILD ?= build-sanitize

.PHONY: all deps configure build demo test test-sanitize bench bench-torch bench-nerf clean

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

$(SANITIZE_BUILD)/CMakeCache.txt: | deps
	@cmake -S . -B $(SANITIZE_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" -DNFIELD_SANITIZE=$(SANITIZE) \
	  -DNFIELD_MPI=OFF -DNFIELD_PYTHON=OFF -DNFIELD_BUILD_BENCH=OFF -DNFIELD_BUILD_EXAMPLES=OFF \
	  $(CMAKE_FLAGS) >/dev/null

# print_stacktrace: where a UBSan report (fatal: -fno-sanitize-recover) came from.
test-sanitize: $(SANITIZE_BUILD)/CMakeCache.txt
	@cmake --build $(SANITIZE_BUILD) -j $(JOBS) --target nfield_sanitize_tests
	@cd $(SANITIZE_BUILD) && UBSAN_OPTIONS=print_stacktrace=1 ctest --output-on-failure -j $(JOBS) -L sanitize

bench: build
	@$(BUILD)/bin/nfield bench

bench-torch: build
	@NFIELD_WITH_TORCH=1 bash scripts/install_deps.sh
	@bash bench/compare_torch.sh $(BUILD)

bench-nerf: build
	@NFIELD_WITH_TORCH=1 bash scripts/install_deps.sh
	@bash bench/compare_nerf.sh $(BUILD)

clean:
	@rm -rf $(BUILD) $(SANITIZE_BUILD)
