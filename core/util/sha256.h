// SHA-256 (FIPS 180-4) through OpenSSL's EVP interface, for content keys and checksums.
#pragma once

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>

// OpenSSL's EVP_MD_CTX, declared here so that this header does not need OpenSSL's (photond_core
// links OpenSSL privately).
struct evp_md_ctx_st;

namespace photond {

using Sha256Digest = std::array<uint8_t, 32>;

/// An incremental SHA-256. Small updates are gathered in an internal buffer, so hashing many
/// small values costs about as much as hashing one large span.
///
/// The typed helpers hash arithmetic values and enums in little-endian byte order whatever the
/// machine, so digests of values do not depend on the host. Strings and spans are length-prefixed:
/// update_string("ab") + update_string("c") differs from update_string("a") + update_string("bc").
///
/// OpenSSL failures (out of memory, or SHA-256 unavailable in its crypto provider: not in a working
/// installation) throw std::runtime_error; nothing else throws.
class Sha256 {
public:
    Sha256();
    ~Sha256();
    Sha256(Sha256&&) noexcept;
    Sha256& operator=(Sha256&&) noexcept;
    Sha256(const Sha256&) = delete;
    Sha256& operator=(const Sha256&) = delete;

    /// Raw bytes, no length prefix.
    void update(std::span<const uint8_t> bytes);

    /// One trivially copyable value without padding (an integer, float, enum, or a packed struct
    /// of them). Arithmetic values and enums are hashed little-endian; a float's bit pattern is
    /// hashed as is (callers normalise -0 or NaN where equal values must hash equally).
    template <class T>
    void update_value(const T& value);

    /// A span of such values, prefixed with its length (u64).
    template <class T>
    void update_values(std::span<const T> values);

    /// A string's bytes, prefixed with its length (u64).
    void update_string(std::string_view text);

    /// The digest of everything hashed so far; the hasher then starts over, empty.
    Sha256Digest finish();

    /// Lower-case hexadecimal, 64 characters.
    static std::string hex(const Sha256Digest& digest);

private:
    struct ContextDeleter {
        void operator()(evp_md_ctx_st* context) const;
    };

    void flush();
    void restart();

    std::unique_ptr<evp_md_ctx_st, ContextDeleter> context_;
    std::array<uint8_t, 1024> buffer_{};
    size_t buffered_ = 0;
};

/// SHA-256 of a byte span (no length prefix), as 64 lower-case hexadecimal characters.
std::string sha256_hex(std::span<const uint8_t> bytes);
/// SHA-256 of a byte span (no length prefix).
Sha256Digest sha256(std::span<const uint8_t> bytes);

template <class T>
void Sha256::update_value(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>, "only trivially copyable values can be hashed");
    static_assert(std::has_unique_object_representations_v<T> || std::is_floating_point_v<T>,
                  "padding bytes are indeterminate: hash such a struct field by field");
    std::array<uint8_t, sizeof(T)> bytes;
    std::memcpy(bytes.data(), &value, sizeof(T));
    if constexpr (std::endian::native == std::endian::big &&
                  (std::is_arithmetic_v<T> || std::is_enum_v<T>)) {
        for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
    }
    if (buffered_ + sizeof(T) <= buffer_.size()) {
        std::memcpy(buffer_.data() + buffered_, bytes.data(), sizeof(T));
        buffered_ += sizeof(T);
    } else {
        update(bytes);
    }
}

template <class T>
void Sha256::update_values(std::span<const T> values) {
    update_value(uint64_t(values.size()));
    if constexpr (std::endian::native == std::endian::little || sizeof(T) == 1) {
        static_assert(std::is_trivially_copyable_v<T>);
        static_assert(std::has_unique_object_representations_v<T> || std::is_floating_point_v<T>);
        update({reinterpret_cast<const uint8_t*>(values.data()), values.size_bytes()});
    } else {
        for (const T& value : values) update_value(value);
    }
}

}  // namespace photond
