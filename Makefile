# photond: `make demo` renders the built-in Cornell box; `make test` runs every test.
# Both install the missing Debian packages first (apt-get; skipped when all are present).

BUILD ?= build
JOBS ?= $(shell nproc)
SUDO := $(shell [ "$$(id -u)" -eq 0 ] || echo sudo)
DEBIAN_PACKAGES := cmake g++ make pkg-config libembree-dev libtbb-dev libopenexr-dev libimath-dev \
	libtinygltf-dev libcpp-httplib-dev nlohmann-json3-dev libglm-dev libpng-dev libssl-dev libarchive-dev libgtest-dev \
	libbenchmark-dev curl python3 python3-venv python3-pip python3-setuptools python3-wheel gnuplot-nox libmeshoptimizer-dev libdraco-dev libstb-dev libwebp-dev gltfpack
OUT ?= out
# The tools of the interface checks that ctest runs (tests/server/metrics_exposition_test.cpp:
# promtool; tests/server/openapi_document_test.cpp: npm, which installs the OpenAPI validator into
# the build tree; tests/server/web_page_test.cpp: chromium, driven by puppeteer-core, which npm
# installs into the build tree), as command:package. A command already on the PATH is kept,
# whatever package brought it: NodeSource's nodejs carries its own npm and conflicts with Debian's
# npm package.
TEST_TOOLS := promtool:prometheus node:nodejs npm:npm chromium:chromium
missing_tool_packages = $(shell for t in $(TEST_TOOLS); do \
	command -v $$(echo $$t | cut -d: -f1) >/dev/null || echo $$t | cut -d: -f2; done)

.PHONY: all deps configure build test tsan demo bench clean format

all: build

# $(call install_missing,PACKAGES): apt-get installs those of PACKAGES not installed yet.
install_missing = @missing=$$(for p in $(1); do \
		dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q '^install ok installed' || echo $$p; \
	done); \
	if [ -n "$$missing" ]; then \
		echo "installing Debian packages:" $$missing; \
		$(SUDO) apt-get update -qq && \
		DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing; \
	fi

deps:
	$(call install_missing,$(DEBIAN_PACKAGES) $(missing_tool_packages))

configure: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release

build: configure
	cmake --build $(BUILD) -j$(JOBS)

test: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

# The irradiance cache's concurrency stress test under ThreadSanitizer (run by CI). Tests that run
# on oneTBB's threads are not among them: Debian's libtbb is not instrumented, so ThreadSanitizer
# cannot see its synchronisation and reports races inside TBB's own headers.
tsan: deps
	cmake -S . -B $(BUILD)-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPHOTOND_SANITIZE=thread
	cmake --build $(BUILD)-tsan -j$(JOBS) --target irradiance_cache_test
	TSAN_OPTIONS=halt_on_error=1 $(BUILD)-tsan/tests/irradiance_cache_test --gtest_filter='IrradianceCache.Concurrent*:IrradianceCache.Octree*'

# The stress suite and the fast core tests under AddressSanitizer and UndefinedBehaviorSanitizer
# (run by CI). Embree and oneTBB are not instrumented, so leak checking is off. Every test runs;
# a sanitizer report stops the run at once (exit code 86), other failures are listed at the end.
ASAN_TESTS := degenerate_geometry_test degenerate_light_test scale_invariance_test fireflies_test \
	scene_transform_test builtin_scenes_test gltf_loader_test emission_test emission_focus_test analytic_lighting_test \
	tile_renderer_test photon_test kd_tree_test photon_map_test photon_map_io_test photon_tracer_test \
	final_gather_test exr_io_test png_preview_test environment_light_test material_textures_test alpha_test \
	clearcoat_test gltf_loader_fuzz_test gltf_webp_test gltf_deformation_test exr_assemble_test irradiance_cache_io_test caustic_skip_test \
	light_tree_test irradiance_wave_merge_test preview_renderer_test homogeneous_medium_test atmosphere_test volume_photon_test \
	radiance_cache_test scattering_solid_test image_metrics_test glossy_gather_test irradiance_bound_grid_test

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

# libFuzzer targets (README.md, "Fuzzing"): clang 14, every library with ASan + UBSan and the
# fuzzer's coverage, each target run FUZZ_SECONDS on a scratch copy of its committed corpus
# (fuzz/corpus/<target>) with its dictionary. Any crash, hang (FUZZ_TIMEOUT seconds on one input),
# sanitizer report or out-of-memory (FUZZ_RSS_MB) fails the run; the input lands in
# $(FUZZ_BUILD)/runs/<target>/. `make fuzz-ci` is the same for 30 s per target (run by CI).
# FUZZ_TARGETS="job gltf" runs some; FUZZ_CMAKE_ARGS=-DCMAKE_CXX_COMPILER_LAUNCHER=ccache.
FUZZ_PACKAGES := clang-14 libfuzzer-14-dev lld-14
FUZZ_BUILD ?= $(BUILD)-fuzz
FUZZ_SECONDS ?= 600
FUZZ_TIMEOUT ?= 25
FUZZ_RSS_MB ?= 2048
FUZZ_TARGETS ?= job gltf photon_map render_cache scene_bundle http_request
FUZZ_CMAKE_ARGS ?=
# Per target: the longest input and the dictionary (fuzz/dict; http_request takes both).
FUZZ_MAX_LEN_job := 4096
FUZZ_MAX_LEN_gltf := 65536
FUZZ_MAX_LEN_photon_map := 16384
FUZZ_MAX_LEN_render_cache := 16384
FUZZ_MAX_LEN_scene_bundle := 65536
FUZZ_MAX_LEN_http_request := 16384
FUZZ_DICTS_job := json
FUZZ_DICTS_gltf := gltf
FUZZ_DICTS_scene_bundle := gltf
FUZZ_DICTS_http_request := http json

.PHONY: fuzz-deps fuzz-build fuzz fuzz-ci
fuzz-deps: deps
	$(call install_missing,$(FUZZ_PACKAGES))

fuzz-build: fuzz-deps
	cmake -S . -B $(FUZZ_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++-14 \
		-DCMAKE_EXE_LINKER_FLAGS=-fuse-ld=lld -DPHOTOND_FUZZ=ON \
		-DBUILD_TESTING=OFF $(FUZZ_CMAKE_ARGS)
	cmake --build $(FUZZ_BUILD) -j$(JOBS) --target fuzzers

fuzz: $(addprefix fuzz-run-,$(FUZZ_TARGETS))

# One target's run (not .PHONY: make skips pattern rules for phony targets; no such file exists).
fuzz-run-%: fuzz-build
	$(if $(FUZZ_MAX_LEN_$*),,$(error unknown fuzz target '$*' (FUZZ_TARGETS: job gltf photon_map render_cache scene_bundle http_request)))
	@run=$(FUZZ_BUILD)/runs/$*; rm -rf $$run; mkdir -p $$run/corpus; \
		cp fuzz/corpus/$*/* $$run/corpus/; \
		dict=""; \
		if [ -n "$(FUZZ_DICTS_$*)" ]; then \
			cat $(foreach d,$(FUZZ_DICTS_$*),fuzz/dict/$(d).dict) > $$run/dictionary; dict=-dict=$$run/dictionary; \
		fi; \
		echo "== $*_fuzzer: $(FUZZ_SECONDS) s, corpus $$(ls $$run/corpus | wc -l) inputs, -max_len=$(FUZZ_MAX_LEN_$*)"; \
		ASAN_OPTIONS=detect_leaks=0 \
		UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
			$(FUZZ_BUILD)/fuzz/$*_fuzzer $$run/corpus $$dict -max_len=$(FUZZ_MAX_LEN_$*) \
			-max_total_time=$(FUZZ_SECONDS) -timeout=$(FUZZ_TIMEOUT) -rss_limit_mb=$(FUZZ_RSS_MB) \
			-print_final_stats=1 -artifact_prefix=$$run/ > $$run/log 2>&1; rc=$$?; \
		grep -E '^(stat::|#[0-9]+ *DONE)' $$run/log; \
		if [ $$rc -ne 0 ]; then tail -n 60 $$run/log; echo "$*_fuzzer: finding (exit $$rc), see $$run"; exit 1; fi

fuzz-ci:
	$(MAKE) fuzz FUZZ_SECONDS=30

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
	$(BUILD)/bench/schedule_simulation cornell-box-diffuse 512 512 3
	python3 bench/photon_series.py --photond $(BUILD)/server/photond
	python3 bench/large_scene.py --photond $(BUILD)/server/photond
	python3 bench/run_benchmark.py --photond $(BUILD)/server/photond $(BENCH_ARGS)
	python3 bench/gltf_samples.py --photond $(BUILD)/server/photond
	python3 bench/radiance_cache_tradeoff.py --photond $(BUILD)/server/photond
	$(MAKE) bench-web

# photond against another renderer: the Khronos samples in Blender's Cycles and in photond, same
# camera, sky and pixel filter (bench/cycles_compare.py; Debian's blender and the python3-numpy
# its glTF importer needs; about 20 minutes at 1024 spp). Not in `bench`: Blender is a large
# install.
CYCLES_SPP ?= 1024
.PHONY: cycles-compare
cycles-compare: build
	$(call install_missing,blender python3-numpy)
	python3 bench/cycles_compare.py --photond $(BUILD)/server/photond --cycles-spp $(CYCLES_SPP)

# glTF written by another tool: scenes built in Blender, exported by its glTF exporter
# (photometric lights, alpha clip, normal maps, emission strength) and rendered there by Cycles as
# built; photond renders the exported files (bench/blender_authored.py; about 12 minutes at
# 1024 spp). Not in `bench`, for the same reason as cycles-compare.
.PHONY: blender-authored
blender-authored: build
	$(call install_missing,blender python3-numpy)
	python3 bench/blender_authored.py --photond $(BUILD)/server/photond --cycles-spp $(CYCLES_SPP) --principled

# The web page's time goals (README.md, "The web page"): first paint under 200 ms and a live tile
# within 50 ms of its event, asserted. ctest runs the same test and prints the figures only.
.PHONY: bench-web
bench-web: build
	PHOTOND_WEB_TIME_GOALS=1 $(BUILD)/tests/web_page_test --gtest_filter=WebPage.InChromium

# 200 concurrent clients (submitters, event and tile streams, slow readers, slowloris) on a real
# daemon for LOAD_SECONDS, with the /healthz p99 goal of 50 ms (bench/load_test.py). ctest runs a
# short version without the latency goal.
LOAD_SECONDS ?= 60
.PHONY: load
load: build
	python3 bench/load_test.py --photond $(BUILD)/server/photond --clients 200 \
		--seconds $(LOAD_SECONDS) --latency-goal-ms 50 --json bench/results/load_test.json

# The web page (README.md, "The web page") in headless chromium with a 4096 x 4096 job of 16,384
# tiles: every tile drawn, the canvas equal to preview.png, the browser's memory measured against
# 500 MB (WebPage.DISABLED_LargeJobInChromium in tests/server/web_page_test.cpp; ctest runs the
# short WebPage.InChromium). WEB_LARGE_SIZE=2048 for a smaller one.
WEB_LARGE_SIZE ?= 4096
.PHONY: test-web-large web-screenshots
test-web-large: build
	PHOTOND_WEB_LARGE_SIZE=$(WEB_LARGE_SIZE) $(BUILD)/tests/web_page_test \
		--gtest_also_run_disabled_tests --gtest_filter=WebPage.DISABLED_LargeJobInChromium

# docs/images/web-queue.png and docs/images/web-job.png, taken by WebPage.InChromium.
web-screenshots: build
	PHOTOND_WEB_SCREENSHOTS=$(CURDIR)/docs/images $(BUILD)/tests/web_page_test --gtest_filter=WebPage.InChromium

# deploy/slurm/ on a real single-node Slurm cluster started by the test (Debian's slurmctld,
# slurmd and munge; as root): 2 views x 4 regions, assembled frames byte-identical to photond
# render (tests/slurm/slurm_cluster_test.sh; run by CI, about 15 s).
SLURM_PACKAGES := slurmctld slurmd slurm-client munge
.PHONY: test-slurm
test-slurm: build
	$(call install_missing,$(SLURM_PACKAGES))
	bash tests/slurm/slurm_cluster_test.sh $(BUILD)/server/photond

# deploy/ checked against the built binary (tests/deploy/check_deploy.py: the unit with
# systemd-analyze verify and its ExecStart run under the unit's rules, the Dockerfile, the
# Kubernetes manifests, shell scripts with shellcheck; run by CI).
DEPLOY_PACKAGES := python3-yaml systemd shellcheck
.PHONY: test-deploy
test-deploy: build
	$(call install_missing,$(DEPLOY_PACKAGES))
	python3 tests/deploy/check_deploy.py $(BUILD)/server/photond

# deploy/docker/Dockerfile's runtime stage without Docker: a debootstrap Debian 12 root file
# system, the stage's RUN line, the built binaries, the ENTRYPOINT and HEALTHCHECK run in it
# (tests/deploy/container_rootfs_test.sh; as root; run by CI, about 35 s the first time).
.PHONY: test-container
test-container: build
	$(call install_missing,debootstrap curl)
	bash tests/deploy/container_rootfs_test.sh $(BUILD)

format:
	find core protocol server clients tests bench -name '*.h' -o -name '*.cpp' | xargs clang-format -i

clean:
	rm -rf $(BUILD) $(OUT)
