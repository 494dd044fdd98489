# photond: `make demo` renders the built-in Cornell box; `make test` runs every test.
# Both install the missing Debian packages first (apt-get; skipped when all are present).

BUILD ?= build
JOBS ?= $(shell nproc)
SUDO := $(shell [ "$$(id -u)" -eq 0 ] || echo sudo)
DEBIAN_PACKAGES := cmake g++ make pkg-config libembree-dev libtbb-dev libopenexr-dev libimath-dev \
	libtinygltf-dev libcpp-httplib-dev nlohmann-json3-dev libglm-dev libpng-dev libssl-dev libgtest-dev \
	libbenchmark-dev curl
OUT ?= out

.PHONY: all deps configure build test tsan demo bench clean format

all: build

deps:
	@missing=$$(for p in $(DEBIAN_PACKAGES); do \
		dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q '^install ok installed' || echo $$p; \
	done); \
	if [ -n "$$missing" ]; then \
		echo "installing Debian packages:" $$missing; \
		$(SUDO) apt-get update -qq && \
		DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing; \
	fi

configure: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release

build: configure
	cmake --build $(BUILD) -j$(JOBS)

test: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

# The irradiance cache's concurrency stress test under ThreadSanitizer (run by CI).
tsan: deps
	cmake -S . -B $(BUILD)-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPHOTOND_SANITIZE=thread
	cmake --build $(BUILD)-tsan -j$(JOBS) --target irradiance_cache_test
	TSAN_OPTIONS=halt_on_error=1 $(BUILD)-tsan/tests/irradiance_cache_test --gtest_filter='IrradianceCache.Concurrent*:IrradianceCache.Octree*'

demo: build
	./deploy/demo.sh $(BUILD) $(OUT)

bench: build
	$(BUILD)/bench/ray_throughput_bench
	$(BUILD)/bench/photon_tracing_bench
	$(BUILD)/bench/kd_tree_bench
	$(BUILD)/bench/http_bench

format:
	find core protocol server clients tests bench -name '*.h' -o -name '*.cpp' | xargs clang-format -i

clean:
	rm -rf $(BUILD) $(OUT)
