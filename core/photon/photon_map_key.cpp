#include "core/photon/photon_map_key.h"

#include "core/scene/scene_hash.h"
#include "core/util/sha256.h"

namespace photond {

// Fires when a field is added to PhotonTracingSettings: add it to photon_map_key if the maps
// depend on it, then update the size here.
static_assert(sizeof(void*) != 8 || sizeof(PhotonTracingSettings) == 56,
              "PhotonTracingSettings changed: add the new field to photon_map_key if the maps "
              "depend on it");

std::string photon_map_key(const Scene& scene, const PhotonTracingSettings& settings) {
    Sha256 hasher;
    hasher.update_string("photond photon-map key");
    hasher.update_value(kPhotonMapAlgorithmVersion);
    hasher.update(scene_content_hash(scene));
    hasher.update_value(uint32_t(settings.global_photons));
    hasher.update_value(uint32_t(settings.caustic_photons));
    hasher.update_value(uint32_t(settings.volume_photons));
    hasher.update_value(uint64_t(settings.seed));
    hasher.update_value(int32_t(settings.max_bounces));
    hasher.update_value(uint32_t(settings.max_emitted_per_stored));
    hasher.update_value(uint32_t(settings.irradiance_stride));
    hasher.update_value(uint32_t(settings.k_irradiance));
    return "pm1-" + Sha256::hex(hasher.finish());
}

}  // namespace photond
