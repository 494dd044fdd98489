// The irradiance-cache importer (core/integrators/irradiance_cache_io.h), as a render on another
// node reads a view's cache: deserialize_irradiance_cache with any key, and
// read_irradiance_cache_key.
//
// A file ends with the SHA-256 of everything before it, which random mutations never match, so
// the checks behind it (key, settings, counts, the records and the octree's structure) would go
// untested. The first input byte therefore chooses: odd, the rest of the input is the file
// without its checksum and the fuzzer appends the right one; even, the rest is taken as it is
// (fuzz/corpus/render_cache holds both kinds, made from real caches of small scenes).
//
// An accepted cache must serialise back byte for byte (the file holds the exact state) and answer
// lookups: near its records and at its nodes' centres, on the root-to-leaf path and widened.
#include <algorithm>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "core/integrators/irradiance_cache_io.h"
#include "fuzz/checksummed_input.h"

namespace {

void lookups(const photond::IrradianceCache& cache) {
    photond::Color e(0.0f);
    const size_t records = std::min<size_t>(cache.size(), 16);
    for (size_t i = 0; i < records; ++i) {
        const photond::IrradianceRecord& r = cache.records()[i];
        for (float scale : {1.0f, 2.0f}) {
            (void)cache.interpolate(r.position, r.normal, &e, scale);
            (void)cache.interpolate(r.position + 0.1f * r.radius, -r.normal, &e, scale);
        }
    }
    const size_t nodes = std::min<size_t>(cache.nodes().size(), 16);
    for (size_t i = 0; i < nodes; ++i) {
        (void)cache.interpolate(cache.nodes()[i].center, photond::Vec3(0.0f, 1.0f, 0.0f), &e, 1.5f);
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size == 0) return 0;
    const std::vector<uint8_t> bytes = photond::fuzz::checksummed_file(data, size);
    (void)photond::read_irradiance_cache_key(bytes);
    const photond::Expected<std::unique_ptr<photond::IrradianceCache>> cache =
        photond::deserialize_irradiance_cache(bytes, std::string());
    photond::fuzz::require(cache || !cache.error().message.empty(),
                           "refused with an empty message");
    if (cache) {
        // What was accepted is written back identically (the file holds the exact state).
        const auto again =
            photond::serialize_irradiance_cache(**cache, photond::read_irradiance_cache_key(bytes));
        photond::fuzz::require(again && *again == bytes,
                               "an accepted file is not written back byte for byte");
        lookups(**cache);
    }
    return 0;
}
