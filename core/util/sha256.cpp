#include "core/util/sha256.h"

#include <openssl/evp.h>

#include <stdexcept>

namespace photond {

void Sha256::ContextDeleter::operator()(evp_md_ctx_st* context) const { EVP_MD_CTX_free(context); }

Sha256::Sha256() : context_(EVP_MD_CTX_new()) {
    if (!context_) throw std::runtime_error("SHA-256: OpenSSL could not allocate a digest context");
    restart();
}

Sha256::~Sha256() = default;
Sha256::Sha256(Sha256&&) noexcept = default;
Sha256& Sha256::operator=(Sha256&&) noexcept = default;

void Sha256::restart() {
    buffered_ = 0;
    if (EVP_DigestInit_ex(context_.get(), EVP_sha256(), nullptr) != 1) {
        throw std::runtime_error("SHA-256: OpenSSL could not initialise the digest");
    }
}

void Sha256::flush() {
    if (buffered_ == 0) return;
    if (EVP_DigestUpdate(context_.get(), buffer_.data(), buffered_) != 1) {
        throw std::runtime_error("SHA-256: OpenSSL digest update failed");
    }
    buffered_ = 0;
}

void Sha256::update(std::span<const uint8_t> bytes) {
    if (bytes.empty()) return;
    if (buffered_ + bytes.size() <= buffer_.size()) {
        std::memcpy(buffer_.data() + buffered_, bytes.data(), bytes.size());
        buffered_ += bytes.size();
        return;
    }
    flush();
    if (bytes.size() < buffer_.size()) {
        std::memcpy(buffer_.data(), bytes.data(), bytes.size());
        buffered_ = bytes.size();
    } else if (EVP_DigestUpdate(context_.get(), bytes.data(), bytes.size()) != 1) {
        throw std::runtime_error("SHA-256: OpenSSL digest update failed");
    }
}

void Sha256::update_string(std::string_view text) {
    update_value(uint64_t(text.size()));
    update({reinterpret_cast<const uint8_t*>(text.data()), text.size()});
}

Sha256Digest Sha256::finish() {
    flush();
    Sha256Digest digest{};
    unsigned int length = 0;
    if (EVP_DigestFinal_ex(context_.get(), digest.data(), &length) != 1 ||
        length != digest.size()) {
        throw std::runtime_error("SHA-256: OpenSSL could not finish the digest");
    }
    restart();
    return digest;
}

std::string Sha256::hex(const Sha256Digest& digest) {
    static constexpr char kDigits[] = "0123456789abcdef";
    std::string text(2 * digest.size(), '0');
    for (size_t i = 0; i < digest.size(); ++i) {
        text[2 * i] = kDigits[digest[i] >> 4];
        text[2 * i + 1] = kDigits[digest[i] & 15];
    }
    return text;
}

Sha256Digest sha256(std::span<const uint8_t> bytes) {
    Sha256 hasher;
    hasher.update(bytes);
    return hasher.finish();
}

std::string sha256_hex(std::span<const uint8_t> bytes) { return Sha256::hex(sha256(bytes)); }

}  // namespace photond
