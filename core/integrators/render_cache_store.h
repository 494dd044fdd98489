// Where irradiance caches (render caches) are kept between jobs, by render-cache key
// (PhotonMapIntegrator::render_cache_key): the daemon's and `photond render --cache-dir`'s
// directory (server/render_cache_directory.h) implements it.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "core/util/expected.h"

namespace photond {

class IrradianceCache;

class RenderCacheStore {
public:
    virtual ~RenderCacheStore() = default;
    /// The cache kept under `key` (from memory or disk), or what `build` returns, then kept; says
    /// whether it was kept before. Thread-safe: a key is built once however many ask at once.
    virtual Expected<std::shared_ptr<const IrradianceCache>> get_or_build(
        const std::string& key, const std::function<Expected<std::shared_ptr<const IrradianceCache>>()>& build,
        bool* cache_hit) = 0;
    /// The cache kept under `key`; nullptr when there is none.
    virtual std::shared_ptr<const IrradianceCache> find_cache(const std::string& key) = 0;
};

}  // namespace photond
