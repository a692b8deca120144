# The two set-up commands of the README, and a few helpers.
#   make run    install what is missing, build, serve UI + API on http://127.0.0.1:$(PORT)
#   make test   install what is missing, build, run every test
PORT ?= 8080
HOST ?= 127.0.0.1
BUILD ?= build
BUILD_TYPE ?= RelWithDebInfo
JOBS ?= $(shell nproc)
# DEPS_MODE=build installs only what building needs (docker/install-deps.sh --build: no
# browser, no test framework); empty installs everything, tests included.
DEPS_MODE ?=
# Extra arguments to the first cmake configure of $(BUILD), e.g. CMAKE_ARGS="-DBRDFA_BUILD_TESTS=OFF".
CMAKE_ARGS ?=

.PHONY: all deps web build run test bench soak sanitize format clean

all: build

deps:
	@sh docker/install-deps.sh $(if $(DEPS_MODE),--$(DEPS_MODE))

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(CMAKE_ARGS)

build: deps web $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

# The browser UI: npm packages (CodeMirror, esbuild, playwright-core) from web/package-lock.json,
# bundled by web/build.mjs into web/dist/ (ignored, never committed). Both steps re-run only when
# their inputs changed: `npm ci` when the lock file did, esbuild when a source did.
WEB_SOURCES := web/build.mjs $(shell find web/src -name '*.js' 2>/dev/null)
web: web/dist/main.js

web/node_modules/.package-lock.json: web/package.json web/package-lock.json | deps
	cd web && npm ci --no-audit --no-fund

web/dist/main.js: web/node_modules/.package-lock.json $(WEB_SOURCES)
	cd web && node build.mjs

run: build
	$(BUILD)/server/brdfa-server --host $(HOST) --port $(PORT)

test: build web
	cd $(BUILD) && ctest --output-on-failure -j 1

bench: build
	$(BUILD)/bench/brdfa-bench

# Long versions of the stress tests (make test runs each for 30 s): 10 minutes of mixed
# BRDF/preset traffic from 8 clients against one server.
soak: build
	cd $(BUILD) && BRDFA_RACE_SECONDS=600 ctest --output-on-failure -R '^Races\.'

# The test suite under AddressSanitizer + UndefinedBehaviorSanitizer. The Vulkan loader
# unloads the driver at vkDestroyInstance, which turns the driver's own globals into
# "leaks" in unknown modules; preloading lavapipe keeps it mapped (servers spawned by the
# tests inherit it), so LeakSanitizer reports only real leaks. tests/lsan.supp leaves out what
# the driver itself allocates (indirect leaks of its internal objects after many pipelines).
LVP_ICD := $(firstword $(wildcard /usr/share/vulkan/icd.d/lvp_icd.*.json))
LVP_LIB = $(shell sed -n 's/.*"library_path": *"\([^"]*\)".*/\1/p' $(LVP_ICD))
sanitize: deps web
	cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug -DBRDFA_SANITIZE=ON -DBRDFA_BUILD_BENCH=OFF
	cmake --build build-asan -j $(JOBS)
	cd build-asan && LD_PRELOAD=$(LVP_LIB) ASAN_OPTIONS=verify_asan_link_order=0:detect_leaks=1 \
		LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp \
		UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ctest --output-on-failure -j 1

# Lays out every C++ file as .clang-format says (tests/style/check_format.mjs checks it).
format:
	find renderer server tests bench -name '*.cpp' -o -name '*.h' | xargs clang-format -i --style=file

clean:
	rm -rf $(BUILD) build-asan
