// Joining the EXRs of regions of one frame (`image.region` renders, each written with the
// region as its data window) into the frame's EXR. Every pixel comes from exactly one part and
// the frame is written as write_exr writes a whole render (same tiles, pixel type, channels), so
// parts of a frame rendered on several machines assemble into the bytes one machine would write.
#pragma once

#include <filesystem>
#include <vector>

#include "core/image/exr_io.h"
#include "core/util/expected.h"

namespace photond {

struct AssembledExr {
    std::vector<uint8_t> bytes;  // the frame's EXR
    int width = 0;
    int height = 0;
};

/// Reads the parts and joins them. Refused, naming the file(s): a part that cannot be read, whose
/// display window, channels, pixel type, tiles or compression differ from the first part's, two
/// parts that overlap, and a frame the parts do not cover (the missing rectangle is named).
Expected<AssembledExr> assemble_exr_parts(const std::vector<std::filesystem::path>& parts);

}  // namespace photond
