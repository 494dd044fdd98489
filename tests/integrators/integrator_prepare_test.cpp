// Integrator::prepare, the step before the tiles, through the interface the pipeline uses: the
// photon-map integrator fills its irradiance cache (built once per render-cache key when a store
// keeps them, taken from the store afterwards), the others need no preparation.
#include <gtest/gtest.h>

#include <map>

#include "core/integrators/irradiance_cache.h"
#include "core/integrators/path.h"
#include "core/integrators/photon_mapping.h"
#include "core/integrators/render_cache_store.h"
#include "core/scene/builtin_scenes.h"

namespace photond {
namespace {

// A store in memory: counts builds.
class MemoryStore final : public RenderCacheStore {
public:
    Expected<std::shared_ptr<const IrradianceCache>> get_or_build(
        const std::string& key, const std::function<Expected<std::shared_ptr<const IrradianceCache>>()>& build,
        bool* cache_hit) override {
        if (auto found = caches.find(key); found != caches.end()) {
            *cache_hit = true;
            return found->second;
        }
        *cache_hit = false;
        ++builds;
        auto built = build();
        if (built) caches[key] = *built;
        return built;
    }
    std::shared_ptr<const IrradianceCache> find_cache(const std::string& key) override {
        auto found = caches.find(key);
        return found == caches.end() ? nullptr : found->second;
    }
    std::map<std::string, std::shared_ptr<const IrradianceCache>> caches;
    int builds = 0;
};

struct Fixture {
    std::shared_ptr<const Scene> scene = std::make_shared<const Scene>(make_builtin_scene("cornell-box-diffuse").value());
    std::shared_ptr<const RenderScene> rs = RenderScene::create(EmbreeDevice::create().value(), scene).value();
    std::shared_ptr<const PhotonMaps> maps = [&] {
        PhotonTracingSettings photons;
        photons.global_photons = 5000;
        photons.caustic_photons = 0;
        return std::make_shared<const PhotonMaps>(trace_photons(*rs, photons).value());
    }();
    Camera camera = Camera::create(scene->cameras.at(0), 32, 32).value();

    std::unique_ptr<Integrator> photon_map() const {
        PhotonMapIntegratorSettings settings;
        settings.gather.rays = 16;
        return std::make_unique<PhotonMapIntegrator>(rs, maps, settings);
    }
    PrepareContext context(RenderCacheStore* store, std::string start_from = "") const {
        return PrepareContext{.camera = camera,
                              .camera_desc = scene->cameras.at(0),
                              .width = 32,
                              .height = 32,
                              .photon_map_key = store ? "pm-test" : "",
                              .render_caches = store,
                              .start_from = std::move(start_from),
                              .cancel = nullptr};
    }
};

TEST(IntegratorPrepare, PathTracingNeedsNoPreparation) {
    const Fixture f;
    PathIntegrator path(f.rs);
    EXPECT_TRUE(path.preparation_pass().empty());
    const auto report = static_cast<Integrator&>(path).prepare(f.context(nullptr));
    ASSERT_TRUE(report.has_value());
    EXPECT_FALSE(report->built);
}

TEST(IntegratorPrepare, PhotonMapBuildsItsCacheOncePerKeyWithAStore) {
    const Fixture f;
    MemoryStore store;
    auto first = f.photon_map();
    EXPECT_EQ(first->preparation_pass(), "irradiance_cache");
    const auto built = first->prepare(f.context(&store));
    ASSERT_TRUE(built.has_value()) << built.error().message;
    EXPECT_TRUE(built->built);
    EXPECT_EQ(built->cache_outcome, "miss");
    EXPECT_EQ(built->cache_key.rfind("rc1-", 0), 0u) << built->cache_key;
    EXPECT_GT(built->records, 0u);
    EXPECT_GT(built->waves, 0);
    EXPECT_GT(built->counters.rays, 0u);

    auto second = f.photon_map();
    const auto taken = second->prepare(f.context(&store));
    ASSERT_TRUE(taken.has_value());
    EXPECT_EQ(taken->cache_outcome, "hit");
    EXPECT_EQ(taken->cache_key, built->cache_key);
    EXPECT_EQ(taken->records, built->records);
    EXPECT_EQ(taken->counters.rays, 0u);  // nothing traced
    EXPECT_EQ(store.builds, 1);

    // Without a store: built for this render, nothing kept.
    const auto alone = f.photon_map()->prepare(f.context(nullptr));
    ASSERT_TRUE(alone.has_value());
    EXPECT_TRUE(alone->built);
    EXPECT_TRUE(alone->cache_outcome.empty());
    EXPECT_EQ(alone->records, built->records);  // deterministic
}

TEST(IntegratorPrepare, StartFromNamesWhatIsWrong) {
    const Fixture f;
    MemoryStore store;
    const auto no_store = f.photon_map()->prepare(f.context(nullptr, "rc1-abc"));
    ASSERT_FALSE(no_store.has_value());
    EXPECT_NE(no_store.error().message.find("--cache-dir"), std::string::npos) << no_store.error().message;
    const auto unknown = f.photon_map()->prepare(f.context(&store, "rc1-abc"));
    ASSERT_FALSE(unknown.has_value());
    EXPECT_NE(unknown.error().message.find("no render cache rc1-abc"), std::string::npos) << unknown.error().message;

    const auto first = f.photon_map()->prepare(f.context(&store));
    ASSERT_TRUE(first.has_value());
    const auto started = f.photon_map()->prepare(f.context(&store, first->cache_key));
    ASSERT_TRUE(started.has_value()) << started.error().message;
    EXPECT_EQ(started->start_from, first->cache_key);
    EXPECT_EQ(started->records_reused, first->records);
    EXPECT_NE(started->cache_key, first->cache_key);  // the start is part of the key
}

}  // namespace
}  // namespace photond
