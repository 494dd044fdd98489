// Pinhole perspective and orthographic cameras with ray differentials (Igehy 1999), for
// pixel-footprint-based spacing (irradiance cache, photon radii).
#pragma once

#include <algorithm>
#include <cmath>

#include "core/math/vec.h"
#include "core/scene/scene.h"
#include "core/util/expected.h"

namespace photond {

struct CameraRay {
    Vec3 origin{0.0f};
    Vec3 direction{0.0f, 0.0f, -1.0f};  // unit
    /// Unit directions of the rays through the neighbouring pixel positions (x + 1, y) and
    /// (x, y + 1): the ray differentials of a pinhole camera share the origin; those of an
    /// orthographic camera share the direction (direction_dx = direction) and are offset.
    Vec3 direction_dx{0.0f};
    Vec3 direction_dy{0.0f};
    /// The width of a pixel at the origin, in world units: 0 for a pinhole, the pixel's side
    /// for an orthographic camera. A pixel's footprint at distance t is about
    /// pixel_width + t * (spread of the direction differentials).
    float pixel_width = 0.0f;
    /// The share of the pixel's footprint a texture lookup filters over (mip-map level): the
    /// pixel's n samples, spread over it, average the texture themselves, so each takes
    /// max(1/8, 1/sqrt(n)) of the footprint (as pbrt-v4 scales its ray differentials); a
    /// whole-pixel footprint under 16 samples blurred textures about twice a pixel wide. Set
    /// by the tile renderer; 1 for one sample.
    float texture_footprint_scale = 1.0f;
};

/// CameraRay::texture_footprint_scale for a pixel of `spp` samples.
inline float texture_footprint_scale(int spp) {
    return spp > 1 ? std::max(0.125f, 1.0f / std::sqrt(static_cast<float>(spp))) : 1.0f;
}

class Camera {
public:
    /// Validates the description (finite, look_at != position, up not parallel) and sets up
    /// the raster mapping for an image of width x height pixels.
    static Expected<Camera> create(const CameraDesc& desc, int width, int height);

    /// The ray through the raster position (x, y), x in [0, width), y in [0, height), y down.
    CameraRay generate_ray(float x, float y) const;

    /// Angle subtended by one pixel at the image centre (radians; 0 for an orthographic
    /// camera): the footprint of a pixel at distance d is about d * pixel_angle() / cos.
    float pixel_angle() const { return pixel_angle_; }
    CameraProjection projection() const { return projection_; }
    const Vec3& position() const { return position_; }
    const Vec3& forward() const { return forward_; }
    int width() const { return width_; }
    int height() const { return height_; }

private:
    Vec3 raster_direction(float x, float y) const;
    Vec3 raster_offset(float x, float y) const;  // orthographic: origin offset from position_

    Vec3 position_{0.0f}, forward_{0.0f}, right_{0.0f}, up_{0.0f};
    CameraProjection projection_ = CameraProjection::Perspective;
    float tan_half_vfov_ = 0.0f;
    float ortho_half_height_ = 0.0f;
    float aspect_ = 1.0f;
    int width_ = 0, height_ = 0;
    float pixel_angle_ = 0.0f;
};

}  // namespace photond
