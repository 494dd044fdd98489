#include "core/photon/irradiance_bound_grid.h"

#include <algorithm>

namespace photond {

IrradianceBoundGrid::IrradianceBoundGrid(const PhotonMap& sites, float reach) {
    const std::span<const Photon> photons = sites.tree().photons();
    if (photons.empty() || !(reach >= 0.0f) || !std::isfinite(reach)) return;
    for (const Photon& site : photons) bounds_.extend(site.position);
    bounds_.lower -= Vec3(reach);
    bounds_.upper += Vec3(reach);
    const Vec3 extent = bounds_.extent();
    // Cells no narrower than reach / 2: a site's reach then spans at most 5 of them an axis.
    const float min_cell = 0.5f * reach;
    for (int a = 0; a < 3; ++a) {
        const float cells = min_cell > 0.0f ? std::floor(extent[a] / min_cell) : float(kMaxCellsPerAxis);
        counts_[a] = std::clamp(static_cast<int>(std::min(cells, float(kMaxCellsPerAxis))), 1, kMaxCellsPerAxis);
        inverse_cell_[a] = extent[a] > 0.0f ? float(counts_[a]) / extent[a] : 0.0f;
    }
    cells_.assign(size_t(counts_.x) * size_t(counts_.y) * size_t(counts_.z), 0.0f);
    for (const Photon& site : photons) {
        const float value = luminance(site.flux());
        const glm::ivec3 lo = cell_of(site.position - Vec3(reach));
        const glm::ivec3 hi = cell_of(site.position + Vec3(reach));
        for (int z = lo.z; z <= hi.z; ++z)
            for (int y = lo.y; y <= hi.y; ++y)
                for (int x = lo.x; x <= hi.x; ++x) {
                    float& cell = cells_[index({x, y, z})];
                    cell = std::max(cell, value);
                }
    }
}

glm::ivec3 IrradianceBoundGrid::cell_of(const Vec3& p) const {
    return glm::clamp(glm::ivec3(glm::floor((p - bounds_.lower) * inverse_cell_)), glm::ivec3(0), counts_ - 1);
}

size_t IrradianceBoundGrid::index(const glm::ivec3& cell) const {
    return (size_t(cell.z) * size_t(counts_.y) + size_t(cell.y)) * size_t(counts_.x) + size_t(cell.x);
}

float IrradianceBoundGrid::bound(const Vec3& p) const {
    // Written so that NaN coordinates fail too.
    if (!(p.x >= bounds_.lower.x && p.x <= bounds_.upper.x && p.y >= bounds_.lower.y && p.y <= bounds_.upper.y &&
          p.z >= bounds_.lower.z && p.z <= bounds_.upper.z))
        return 0.0f;
    return cells_[index(cell_of(p))];
}

}  // namespace photond
