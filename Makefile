# photond: `make demo` renders the built-in Cornell box; `make test` runs every test.
# Both install the missing Debian packages first (apt-get; skipped when all are present).

BUILD ?= build
JOBS ?= $(shell nproc)
SUDO := $(shell [ "$$(id -u)" -eq 0 ] || echo sudo)
DEBIAN_PACKAGES := cmake g++ make pkg-config libembree-dev libtbb-dev libopenexr-dev libimath-dev \
	libtinygltf-dev libcpp-httplib-dev nlohmann-json3-dev libglm-dev libpng-dev libssl-dev libarchive-dev libgtest-dev \
	libbenchmark-dev curl python3 gnuplot-nox libmeshoptimizer-dev libdraco-dev libstb-dev gltfpack
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

# The stress suite and the fast core tests under AddressSanitizer and UndefinedBehaviorSanitizer
# (run by CI). Embree and oneTBB are not instrumented, so leak checking is off. Every test runs;
# a sanitizer report stops the run at once (exit code 86), other failures are listed at the end.
ASAN_TESTS := degenerate_geometry_test degenerate_light_test scale_invariance_test fireflies_test \
	scene_transform_test builtin_scenes_test gltf_loader_test emission_test analytic_lighting_test \
	tile_renderer_test photon_test kd_tree_test photon_map_test photon_map_io_test photon_tracer_test \
	final_gather_test exr_io_test png_preview_test environment_light_test material_textures_test alpha_test \
	clearcoat_test

.PHONY: asan
asan: deps
	cmake -S . -B $(BUILD)-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPHOTOND_SANITIZE=address,undefined
	cmake --build $(BUILD)-asan -j$(JOBS) --target $(ASAN_TESTS)
	@failed=""; for t in $(ASAN_TESTS); do \
		echo "== $$t (ASan + UBSan)"; \
		ASAN_OPTIONS=detect_leaks=0:exitcode=86 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1:exitcode=86 \
			$(BUILD)-asan/tests/$$t --gtest_brief=1; rc=$$?; \
		if [ $$rc -eq 86 ]; then echo "$$t: sanitizer error"; exit 1; fi; \
		if [ $$rc -ne 0 ]; then failed="$$failed $$t"; fi; \
	done; \
	if [ -n "$$failed" ]; then echo "tests failed (no sanitizer report):$$failed"; exit 1; fi

demo: build
	./deploy/demo.sh $(BUILD) $(OUT)

# The micro-benchmarks, then the run-time-against-error sweep (bench/README.md): prints the
# table and writes bench/results/ (CSV, Markdown, error_vs_time.png). BENCH_ARGS=--quick for a
# short sweep; BENCH_ARGS="--scenes cornell-box-diffuse --repeats 5" and so on.
BENCH_ARGS ?=
bench: build
	$(BUILD)/bench/ray_throughput_bench
	$(BUILD)/bench/photon_tracing_bench
	$(BUILD)/bench/kd_tree_bench
	$(BUILD)/bench/http_bench
	python3 bench/run_benchmark.py --photond $(BUILD)/server/photond $(BENCH_ARGS)
	python3 bench/gltf_samples.py --photond $(BUILD)/server/photond

format:
	find core protocol server clients tests bench -name '*.h' -o -name '*.cpp' | xargs clang-format -i

clean:
	rm -rf $(BUILD) $(OUT)
