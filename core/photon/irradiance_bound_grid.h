// An upper bound of the irradiance at the nearest precomputed-irradiance site (PhotonMap::
// nearest_irradiance) within a search radius of a point, found in one array read: a coarse grid
// over the sites whose every cell holds the largest luminance among the sites within the radius
// of some point of the cell. The caustic map's visibility test at visible points
// (CausticVisibility::may_show) reads it first and searches the sites only where the
// bound could show.
#pragma once

#include <vector>

#include "core/photon/photon_map.h"
#include "core/scene/scene.h"

namespace photond {

class IrradianceBoundGrid {
public:
    IrradianceBoundGrid() = default;
    /// Over the sites of `sites` (a map of make_irradiance_site photons), for searches of radius
    /// `reach`. At most kMaxCellsPerAxis cells along an axis, none narrower than half of `reach`,
    /// so that a site touches at most 5 cells along each axis.
    IrradianceBoundGrid(const PhotonMap& sites, float reach);

    bool empty() const { return cells_.empty(); }
    /// The largest luminance of the sites within `reach` of p, or more; 0 where none can be (p
    /// beyond every site's reach, or not finite). Undefined for an empty grid.
    float bound(const Vec3& p) const;
    size_t bytes() const { return cells_.size() * sizeof(float); }

    static constexpr int kMaxCellsPerAxis = 32;

private:
    glm::ivec3 cell_of(const Vec3& p) const;  // clamped into the grid
    size_t index(const glm::ivec3& cell) const;

    Bounds3 bounds_;  // the sites' bounds widened by reach
    Vec3 inverse_cell_{0.0f};
    glm::ivec3 counts_{0};
    std::vector<float> cells_;
};

}  // namespace photond
