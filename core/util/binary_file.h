// The pieces shared by photond's versioned binary artifact formats (core/photon/photon_map_io.h,
// core/integrators/irradiance_cache_io.h): little-endian field writing and bounds-checked field
// reading with error text, and files read only when their magic matches (written with
// core/util/file_io.h).
#pragma once

#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/util/expected.h"
#include "core/util/file_io.h"  // write_file_atomically, for the formats

namespace photond {

/// Appends fields to a byte vector: integers little-endian, floats as their IEEE bits.
class ByteWriter {
public:
    /// Raw bytes, in this machine's order.
    void put_bytes(const void* data, size_t size) {
        const uint8_t* bytes = static_cast<const uint8_t*>(data);
        bytes_.insert(bytes_.end(), bytes, bytes + size);
    }
    void put_u8(uint8_t value) { bytes_.push_back(value); }
    void put_u32(uint32_t value) {
        for (int i = 0; i < 4; ++i) bytes_.push_back(uint8_t(value >> (8 * i)));
    }
    void put_u64(uint64_t value) {
        for (int i = 0; i < 8; ++i) bytes_.push_back(uint8_t(value >> (8 * i)));
    }
    void put_f32(float value) { put_u32(std::bit_cast<uint32_t>(value)); }
    void reserve(size_t size) { bytes_.reserve(size); }
    std::vector<uint8_t>& bytes() { return bytes_; }

private:
    std::vector<uint8_t> bytes_;
};

/// Reads fields from bytes[0, end) and never past it. The first read that does not fit, or the
/// first fail(), sets the error; every read after it fails. `field` names what is read, for the
/// message: "truncated <data_name> data: <field> at byte N needs M bytes, K remain".
class ByteReader {
public:
    /// data_name must outlive the reader (a string literal: "photon-map").
    ByteReader(std::span<const uint8_t> bytes, size_t end, const char* data_name)
        : bytes_(bytes), end_(end), data_name_(data_name) {}

    size_t position() const { return position_; }
    size_t remaining() const { return end_ - position_; }
    const std::string& error() const { return error_; }

    /// Raw bytes, in the file's order.
    bool get_bytes(void* data, size_t size, const char* field) {
        if (!error_.empty()) return false;
        if (size > remaining()) {
            truncated(size, field);
            return false;
        }
        if (size > 0) std::memcpy(data, bytes_.data() + position_, size);
        position_ += size;
        return true;
    }
    bool get_u8(uint8_t& value, const char* field) { return get_bytes(&value, 1, field); }
    bool get_u32(uint32_t& value, const char* field) {
        std::array<uint8_t, 4> b;
        if (!get_bytes(b.data(), b.size(), field)) return false;
        value = uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
        return true;
    }
    bool get_u64(uint64_t& value, const char* field) {
        std::array<uint8_t, 8> b;
        if (!get_bytes(b.data(), b.size(), field)) return false;
        value = 0;
        for (int i = 7; i >= 0; --i) value = (value << 8) | b[i];
        return true;
    }
    bool get_f32(float& value, const char* field) {
        uint32_t bits = 0;
        if (!get_u32(bits, field)) return false;
        value = std::bit_cast<float>(bits);
        return true;
    }
    /// A u8 that must be 0 or 1.
    bool get_flag(bool& value, const char* field);
    /// Sets the error unless one is set already; returns false.
    bool fail(std::string message) {
        if (error_.empty()) error_ = std::move(message);
        return false;
    }

private:
    void truncated(size_t size, const char* field);

    std::span<const uint8_t> bytes_;
    size_t end_;
    const char* data_name_;
    size_t position_ = 0;
    std::string error_;
};

/// A regular file's bytes, read whole only if they start with magic: otherwise only the first
/// magic.size() bytes (or fewer), so that a large foreign file is not read whole and the format's
/// parser refuses it by its magic. A file that shrinks while it is read comes back short (a
/// format's checksum must catch it). Messages start with path.
Expected<std::vector<uint8_t>> read_file_with_magic(const std::filesystem::path& path,
                                                    std::span<const uint8_t> magic);

}  // namespace photond
