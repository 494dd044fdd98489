#include "core/camera/camera.h"

#include <string>

namespace photond {

Expected<Camera> Camera::create(const CameraDesc& desc, int width, int height) {
    if (width <= 0 || height <= 0) return Error{"camera: the image size must be positive"};
    if (!is_finite(desc.position) || !is_finite(desc.look_at) || !is_finite(desc.up))
        return Error{"camera '" + desc.name + "': non-finite position, target or up vector"};
    const Vec3 view = desc.look_at - desc.position;
    const float view_length = glm::length(view);
    if (!(view_length > 0.0f) || !std::isfinite(view_length))
        return Error{"camera '" + desc.name + "': look_at equals the camera position"};
    const bool orthographic = desc.projection == CameraProjection::Orthographic;
    if (!orthographic && !(desc.vfov_deg > 0.0f && desc.vfov_deg < 180.0f))
        return Error{"camera '" + desc.name + "': vertical field of view must be in (0, 180) degrees"};
    if (orthographic && !(desc.ortho_half_height > 0.0f && std::isfinite(desc.ortho_half_height)))
        return Error{"camera '" + desc.name + "': the orthographic half-height (ymag) must be positive"};
    Camera c;
    c.projection_ = desc.projection;
    c.position_ = desc.position;
    c.forward_ = view / view_length;
    const Vec3 right = glm::cross(c.forward_, desc.up);
    const float right_length = glm::length(right);
    if (!(right_length > 1e-6f * glm::length(desc.up)))
        return Error{"camera '" + desc.name + "': the up vector is parallel to the view direction"};
    c.right_ = right / right_length;
    c.up_ = glm::cross(c.right_, c.forward_);
    c.width_ = width;
    c.height_ = height;
    // The image's aspect ratio wins: a glTF aspectRatio that disagrees would stretch the image.
    c.aspect_ = static_cast<float>(width) / static_cast<float>(height);
    if (orthographic) {
        // The image's aspect ratio wins here too: the half-width is ymag * width / height.
        c.ortho_half_height_ = desc.ortho_half_height;
        return c;
    }
    c.tan_half_vfov_ = std::tan(0.5f * desc.vfov_deg * kPi / 180.0f);
    c.pixel_angle_ = 2.0f * std::atan(c.tan_half_vfov_ / (0.5f * static_cast<float>(height)) * 0.5f);
    return c;
}

Vec3 Camera::raster_offset(float x, float y) const {
    const float ndc_x = (2.0f * x / static_cast<float>(width_) - 1.0f) * aspect_ * ortho_half_height_;
    const float ndc_y = (1.0f - 2.0f * y / static_cast<float>(height_)) * ortho_half_height_;
    return ndc_x * right_ + ndc_y * up_;
}

Vec3 Camera::raster_direction(float x, float y) const {
    const float ndc_x = (2.0f * x / static_cast<float>(width_) - 1.0f) * aspect_ * tan_half_vfov_;
    const float ndc_y = (1.0f - 2.0f * y / static_cast<float>(height_)) * tan_half_vfov_;
    return glm::normalize(forward_ + ndc_x * right_ + ndc_y * up_);
}

CameraRay Camera::generate_ray(float x, float y) const {
    CameraRay ray;
    if (projection_ == CameraProjection::Orthographic) {
        // Parallel rays from the image plane through the camera position: the differentials
        // move the origin by one pixel and keep the direction.
        ray.origin = position_ + raster_offset(x, y);
        ray.direction = forward_;
        ray.direction_dx = forward_;
        ray.direction_dy = forward_;
        ray.pixel_width = 2.0f * ortho_half_height_ / static_cast<float>(height_);
        return ray;
    }
    ray.origin = position_;
    ray.direction = raster_direction(x, y);
    ray.direction_dx = raster_direction(x + 1.0f, y);
    ray.direction_dy = raster_direction(x, y + 1.0f);
    return ray;
}

}  // namespace photond
