# The two set-up commands of the README, and a few helpers.
#   make run    install what is missing, build, serve UI + API on http://127.0.0.1:$(PORT)
#   make test   install what is missing, build, run every test
PORT ?= 8080
HOST ?= 127.0.0.1
BUILD ?= build
BUILD_TYPE ?= RelWithDebInfo
JOBS ?= $(shell nproc)

.PHONY: all deps build run test bench sanitize clean

all: build

deps:
	@sh docker/install-deps.sh

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE)

build: deps $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

run: build
	$(BUILD)/server/brdfa-server --host $(HOST) --port $(PORT)

test: build
	cd $(BUILD) && ctest --output-on-failure -j 1

bench: build
	$(BUILD)/bench/brdfa-bench

# The test suite under AddressSanitizer + UndefinedBehaviorSanitizer. The Vulkan loader
# unloads the driver at vkDestroyInstance, which turns the driver's own globals into
# "leaks" in unknown modules; preloading lavapipe keeps it mapped (servers spawned by the
# tests inherit it), so LeakSanitizer reports only real leaks. tests/lsan.supp leaves out what
# the driver itself allocates (indirect leaks of its internal objects after many pipelines).
LVP_ICD := $(firstword $(wildcard /usr/share/vulkan/icd.d/lvp_icd.*.json))
LVP_LIB = $(shell sed -n 's/.*"library_path": *"\([^"]*\)".*/\1/p' $(LVP_ICD))
sanitize: deps
	cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug -DBRDFA_SANITIZE=ON -DBRDFA_BUILD_BENCH=OFF
	cmake --build build-asan -j $(JOBS)
	cd build-asan && LD_PRELOAD=$(LVP_LIB) ASAN_OPTIONS=verify_asan_link_order=0:detect_leaks=1 \
		LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp \
		UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ctest --output-on-failure -j 1

clean:
	rm -rf $(BUILD) build-asan
