// 8-bit sRGB PNGs of linear images: previews of renders (exposure, filmic tone curve, sRGB) and
// plain clamped encodings of data images such as error maps.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "core/image/image.h"
#include "core/util/expected.h"

namespace photond {

// ------------------------------------------------------------------------- render previews
//
// Every preview of a render (`photond render --preview`, the daemon's preview.png, finished or
// while rendering) is made by encode_render_preview: each channel is scaled by 2^exposure_ev,
// mapped by filmic_tone_curve, then encoded with the sRGB OETF. The EXR stays linear radiance.

/// Middle grey: automatic exposure maps the image's log-average luminance here.
inline constexpr float kPreviewMiddleGrey = 0.18f;
/// Automatic exposure never goes beyond +-this many stops (2^64 keeps every float finite).
inline constexpr float kMaxAutomaticExposureEv = 64.0f;
/// Highlight protection of automatic exposure: the kHighlightPercentile of the image's positive
/// finite luminances is exposed no brighter than kHighlightCeiling (the filmic curve's 0.91),
/// taking the exposure down from the log-average's by kMaxHighlightProtectionEv stops at most. A
/// sunlit subject over deep shade or a black background (IridescenceSuzanne: 7 % of its frame is
/// not black, mostly shade) no longer comes out white; the cap leaves visible emitters free to
/// clip (LightsPunctualLamp's glowing shade) rather than blacken the rest.
inline constexpr double kHighlightPercentile = 0.9;
inline constexpr float kHighlightCeiling = 2.0f;
inline constexpr float kMaxHighlightProtectionEv = 3.0f;

/// The filmic tone curve of previews: Krzysztof Narkowicz's fit of the ACES reference rendering
/// and output transforms ("ACES Filmic Tone Mapping Curve", 2015),
/// f(x) = x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), clamped to [0, 1]. f(0) = 0, it
/// increases strictly up to x = 7.24 and is 1 (white) from there; f(0.18) = 0.267. Negative and
/// NaN inputs give 0, +inf gives 1.
float filmic_tone_curve(float x);

/// The exposure in stops that maps the image's log-average luminance to kPreviewMiddleGrey:
/// log2(0.18) - mean(log2 Y), Y the Rec. 709 luminance, over the pixels of positive finite
/// luminance (black pixels, e.g. tiles not yet rendered, and NaN or inf are left out) with the
/// darkest and brightest 1 % of them also left out, so that a few hot pixels cannot darken the
/// picture; then lowered, by kMaxHighlightProtectionEv stops at most, until the
/// kHighlightPercentile of all the positive finite luminances (the trimmed ones too) is exposed
/// no brighter than kHighlightCeiling. 0 when no pixel has positive finite luminance (an
/// all-black image). Clamped to +-kMaxAutomaticExposureEv.
float automatic_exposure_ev(const Image& image);

/// The 8-bit sRGB code of one linear channel of a render: scaled by exposure_scale, through
/// filmic_tone_curve, then the sRGB OETF (IEC 61966-2-1), rounded to nearest; NaN and negative
/// values give 0, +inf gives 255.
uint8_t preview_srgb8(float linear, float exposure_scale);

/// A PNG (8-bit RGB, sRGB chunk, no timestamp) of a render in memory; exposure_ev absent means
/// automatic_exposure_ev(image). Error for an empty image or a non-finite exposure.
Expected<std::vector<uint8_t>> encode_render_preview(
    const Image& image, std::optional<float> exposure_ev = std::nullopt);

/// encode_render_preview written with write_file_atomically (core/util/file_io.h).
Status write_render_preview(const std::filesystem::path& path, const Image& image,
                            std::optional<float> exposure_ev = std::nullopt);

// ------------------------------------------------------------------------ plain encodings

/// The 8-bit sRGB code of a linear value after scaling by exposure_scale: clamped to [0, 1],
/// sRGB OETF (IEC 61966-2-1), rounded to nearest; non-finite values give 0. No tone curve.
uint8_t linear_to_srgb8(float linear, float exposure_scale = 1.0f);

/// A PNG (8-bit RGB, sRGB chunk, no timestamp) of `image` in memory through linear_to_srgb8
/// after scaling by 2^exposure_stops, for data images (photond compare --error-png), not for
/// renders; Error for an empty image.
Expected<std::vector<uint8_t>> encode_png_preview(const Image& image, float exposure_stops = 0.0f);

/// encode_png_preview written with write_file_atomically (core/util/file_io.h).
Status write_png_preview(const std::filesystem::path& path, const Image& image,
                         float exposure_stops = 0.0f);

}  // namespace photond
