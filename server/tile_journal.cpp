#include "server/tile_journal.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <system_error>
#include <vector>

#include "core/util/sha256.h"
#include "core/util/file_io.h"

namespace photond::service {

namespace fs = std::filesystem;

namespace {

constexpr char kMagic[8] = {'P', 'H', 'D', 'T', 'I', 'L', 'E', '\n'};
// Bump when the layout or the meaning of the pixels changes: older files are then refused.
constexpr uint32_t kFormatVersion = 1;
constexpr size_t kDigestSize = 32;

void append_u32(std::string& out, uint32_t value) {
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xffu));
}

uint32_t read_u32(const uint8_t* bytes) {
    uint32_t value = 0;
    for (int i = 0; i < 4; ++i) value |= uint32_t{bytes[i]} << (8 * i);
    return value;
}

size_t header_size(const std::string& job_digest) { return sizeof kMagic + 4 + 4 + job_digest.size() + 4 * 4; }

}  // namespace

TileJournal::TileJournal(fs::path directory, std::string job_digest)
    : directory_(std::move(directory)), job_digest_(std::move(job_digest)) {}

fs::path TileJournal::file_of(const PixelRect& rect) const {
    return directory_ / (std::to_string(rect.x0) + "-" + std::to_string(rect.y0) + ".tile");
}

/// The frame's layers in file order: the beauty pass, then the AOVs in the job's order.
template <typename Layers>
auto layers_of(Layers& frame) {
    std::vector<decltype(&frame.beauty)> layers{&frame.beauty};
    for (auto& aov : frame.aovs) layers.push_back(&aov.second);
    return layers;
}

Status TileJournal::save(const PixelRect& rect, const ImageLayers& frame) const {
    if (rect.empty() || !frame.beauty.bounds().contains(rect)) return Error{"tile outside the frame"};
    const auto layers = layers_of(frame);
    std::string bytes;
    bytes.reserve(header_size(job_digest_) + layers.size() * size_t(rect.area()) * 12 + kDigestSize);
    bytes.append(kMagic, sizeof kMagic);
    append_u32(bytes, kFormatVersion);
    append_u32(bytes, static_cast<uint32_t>(job_digest_.size()));
    bytes += job_digest_;
    for (int v : {rect.x0, rect.y0, rect.x1, rect.y1}) append_u32(bytes, static_cast<uint32_t>(v));
    for (const Image* layer : layers)
        for (int y = rect.y0; y < rect.y1; ++y)
            for (int x = rect.x0; x < rect.x1; ++x) {
                const Color& c = layer->at(x, y);
                for (float channel : {c.x, c.y, c.z}) append_u32(bytes, std::bit_cast<uint32_t>(channel));
            }
    const Sha256Digest digest =
        sha256({reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()});
    bytes.append(reinterpret_cast<const char*>(digest.data()), digest.size());

    std::error_code error;
    fs::create_directories(directory_, error);
    if (error) return Error{directory_.string() + ": cannot be created (" + error.message() + ")"};
    return write_file_atomically(file_of(rect), bytes);
}

TileJournal::Restored TileJournal::restore(const PixelRect& rect, ImageLayers& frame, std::string* problem) const {
    const fs::path file = file_of(rect);
    std::error_code error;
    if (!fs::exists(file, error)) return Restored::Missing;
    auto damaged = [&](const std::string& why) {
        if (problem) *problem = file.filename().string() + ": " + why + "; the tile is rendered again";
        std::error_code ignored;
        fs::rename(file, file.string() + ".damaged", ignored);
        return Restored::Damaged;
    };
    if (rect.empty() || !frame.beauty.bounds().contains(rect)) return damaged("the tile lies outside the frame");
    const auto layers = layers_of(frame);
    const Expected<std::vector<uint8_t>> bytes = read_file_bytes(file);
    if (!bytes) return damaged("cannot be read");
    const size_t expected = header_size(job_digest_) + layers.size() * size_t(rect.area()) * 12 + kDigestSize;
    if (bytes->size() != expected)
        return damaged(std::to_string(bytes->size()) + " bytes where " + std::to_string(expected) +
                       " were expected (truncated, or another tile size)");
    const size_t body = bytes->size() - kDigestSize;
    const Sha256Digest digest = sha256({bytes->data(), body});
    if (!std::equal(digest.begin(), digest.end(), bytes->begin() + static_cast<std::ptrdiff_t>(body)))
        return damaged("checksum mismatch");
    const uint8_t* p = bytes->data();
    if (std::memcmp(p, kMagic, sizeof kMagic) != 0) return damaged("not a tile file");
    p += sizeof kMagic;
    if (read_u32(p) != kFormatVersion) return damaged("another tile format version");
    p += 4;
    if (read_u32(p) != job_digest_.size() ||
        std::memcmp(p + 4, job_digest_.data(), job_digest_.size()) != 0)
        return damaged("written for another job description");
    p += 4 + job_digest_.size();
    const int stored[4] = {static_cast<int>(read_u32(p)), static_cast<int>(read_u32(p + 4)),
                           static_cast<int>(read_u32(p + 8)), static_cast<int>(read_u32(p + 12))};
    if (stored[0] != rect.x0 || stored[1] != rect.y0 || stored[2] != rect.x1 || stored[3] != rect.y1)
        return damaged("written for another rectangle");
    p += 16;
    for (Image* layer : layers)
        for (int y = rect.y0; y < rect.y1; ++y)
            for (int x = rect.x0; x < rect.x1; ++x, p += 12)
                layer->at(x, y) = Color(std::bit_cast<float>(read_u32(p)), std::bit_cast<float>(read_u32(p + 4)),
                                        std::bit_cast<float>(read_u32(p + 8)));
    return Restored::Restored;
}

size_t TileJournal::count() const {
    std::error_code error;
    size_t n = 0;
    for (fs::directory_iterator it(directory_, error), end; !error && it != end; it.increment(error))
        if (it->path().extension() == ".tile") ++n;
    return n;
}

void TileJournal::clear() const {
    std::error_code ignored;
    fs::remove_all(directory_, ignored);
}

}  // namespace photond::service
