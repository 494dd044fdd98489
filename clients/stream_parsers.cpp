#include "clients/stream_parsers.h"

#include <algorithm>
#include <cctype>
#include <charconv>

namespace photond::client {
namespace {

std::string to_lower(std::string_view text) {
    std::string lower(text);
    for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return lower;
}

std::string_view trim(std::string_view text) {
    while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
    while (!text.empty() && (text.back() == ' ' || text.back() == '\t' || text.back() == '\r'))
        text.remove_suffix(1);
    return text;
}

// Header sections and delimiter lines are short; anything longer is not a tile stream.
constexpr size_t kMaxHeaderLineBytes = 16 * 1024;
// Consumed bytes are dropped from the buffer once there are this many (or half the buffer).
constexpr size_t kCompactBytes = 64 * 1024;

}  // namespace

// ---------------------------------------------------------------------------------------------
// Server-Sent Events

void SseParser::feed(std::string_view bytes, std::vector<SseEvent>& events) {
    if (skip_line_feed_ && !bytes.empty()) {
        if (bytes.front() == '\n') bytes.remove_prefix(1);
        skip_line_feed_ = false;
    }
    buffer_.append(bytes);
    size_t line_start = 0;
    for (size_t i = 0; i < buffer_.size(); ++i) {
        const char c = buffer_[i];
        if (c != '\n' && c != '\r') continue;
        process_line(std::string_view(buffer_).substr(line_start, i - line_start), events);
        if (c == '\r') {
            if (i + 1 < buffer_.size()) {
                if (buffer_[i + 1] == '\n') ++i;
            } else {
                skip_line_feed_ = true;
            }
        }
        line_start = i + 1;
    }
    buffer_.erase(0, line_start);
}

void SseParser::process_line(std::string_view line, std::vector<SseEvent>& events) {
    if (line.empty()) {
        if (has_data_ || !type_.empty()) {
            SseEvent event;
            if (!type_.empty()) event.type = type_;
            event.data = data_;
            if (!event.data.empty() && event.data.back() == '\n') event.data.pop_back();
            event.id = last_event_id_;
            event.retry_ms = retry_ms_;
            events.push_back(std::move(event));
        }
        data_.clear();
        type_.clear();
        retry_ms_.reset();
        has_data_ = false;
        return;
    }
    if (line.front() == ':') return;  // a comment, e.g. a keep-alive
    std::string_view field = line, value;
    if (const size_t colon = line.find(':'); colon != std::string_view::npos) {
        field = line.substr(0, colon);
        value = line.substr(colon + 1);
        if (!value.empty() && value.front() == ' ') value.remove_prefix(1);
    }
    if (field == "event") {
        type_ = value;
    } else if (field == "data") {
        data_.append(value);
        data_.push_back('\n');
        has_data_ = true;
    } else if (field == "id") {
        if (value.find('\0') == std::string_view::npos) last_event_id_ = value;
    } else if (field == "retry") {
        int ms = 0;
        const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), ms);
        if (error == std::errc() && end == value.data() + value.size()) retry_ms_ = ms;
    }
}

// ---------------------------------------------------------------------------------------------
// multipart

std::string MultipartPart::header(std::string_view name) const {
    const std::string lower = to_lower(name);
    for (const auto& [key, value] : headers)
        if (key == lower) return value;
    return {};
}

std::optional<std::string> multipart_boundary(std::string_view content_type) {
    const size_t semicolon = content_type.find(';');
    if (to_lower(trim(content_type.substr(0, semicolon))).rfind("multipart/", 0) != 0)
        return std::nullopt;
    std::string_view rest =
        semicolon == std::string_view::npos ? std::string_view() : content_type.substr(semicolon);
    while (!rest.empty()) {
        rest.remove_prefix(1);  // the ';'
        const size_t next = rest.find(';');
        std::string_view parameter = trim(rest.substr(0, next));
        rest = next == std::string_view::npos ? std::string_view() : rest.substr(next);
        const size_t equals = parameter.find('=');
        if (equals == std::string_view::npos) continue;
        if (to_lower(trim(parameter.substr(0, equals))) != "boundary") continue;
        std::string_view value = trim(parameter.substr(equals + 1));
        if (value.size() >= 2 && value.front() == '"' && value.back() == '"')
            value = value.substr(1, value.size() - 2);
        if (value.empty()) return std::nullopt;
        return std::string(value);
    }
    return std::nullopt;
}

// The buffer starts with a CRLF so that a delimiter at the very start of the stream matches
// the same "\r\n--boundary" pattern as every later one (RFC 2046: the CRLF belongs to it).
MultipartParser::MultipartParser(std::string boundary)
    : delimiter_("\r\n--" + boundary), buffer_("\r\n") {}

void MultipartParser::fail(std::string message) {
    state_ = State::Failed;
    error_ = std::move(message);
}

bool MultipartParser::feed(std::string_view bytes, std::vector<MultipartPart>& parts) {
    if (state_ == State::Failed) return false;
    if (state_ == State::Finished) return true;
    buffer_.append(bytes);
    while (step(parts)) {
    }
    if (start_ >= kCompactBytes || start_ * 2 >= buffer_.size()) {
        buffer_.erase(0, start_);
        search_from_ = search_from_ > start_ ? search_from_ - start_ : 0;
        start_ = 0;
    }
    return state_ != State::Failed;
}

// Advances by one state when the buffer holds enough bytes; false when it needs more.
bool MultipartParser::step(std::vector<MultipartPart>& parts) {
    const size_t available = buffer_.size() - start_;
    switch (state_) {
        case State::Preamble: {
            const size_t from = std::max(start_, search_from_);
            const size_t at = buffer_.find(delimiter_, from);
            if (at == std::string::npos) {
                // Keep the tail that could be the start of a delimiter split across pieces.
                const size_t keep = delimiter_.size() - 1;
                search_from_ = buffer_.size() > keep ? buffer_.size() - keep : 0;
                start_ = std::max(start_, search_from_);
                return false;
            }
            start_ = at + delimiter_.size();
            state_ = State::AfterDelimiter;
            return true;
        }
        case State::AfterDelimiter: {
            if (available < 2) return false;
            if (buffer_.compare(start_, 2, "--") == 0) {
                start_ = buffer_.size();  // the epilogue is ignored
                state_ = State::Finished;
                return false;
            }
            // Transport padding (spaces) may follow the boundary before the line's CRLF.
            const size_t newline = buffer_.find('\n', start_);
            if (newline == std::string::npos) {
                if (available > kMaxHeaderLineBytes) fail("multipart delimiter line too long");
                return false;
            }
            if (!trim(std::string_view(buffer_).substr(start_, newline - start_)).empty()) {
                fail("unexpected bytes after a multipart boundary");
                return false;
            }
            start_ = newline + 1;
            part_ = MultipartPart();
            state_ = State::Headers;
            return true;
        }
        case State::Headers: {
            const size_t newline = buffer_.find('\n', start_);
            if (newline == std::string::npos) {
                if (available > kMaxHeaderLineBytes) fail("multipart header line too long");
                return false;
            }
            std::string_view line = std::string_view(buffer_).substr(start_, newline - start_);
            if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
            start_ = newline + 1;
            if (line.empty()) {
                body_length_.reset();
                if (const std::string length = part_.header("content-length"); !length.empty()) {
                    size_t n = 0;
                    const auto [end, error] =
                        std::from_chars(length.data(), length.data() + length.size(), n);
                    if (error != std::errc() || end != length.data() + length.size()) {
                        fail("malformed Content-Length in a multipart part: " + length);
                        return false;
                    }
                    body_length_ = n;
                }
                search_from_ = start_;
                state_ = State::Body;
                return true;
            }
            const size_t colon = line.find(':');
            if (colon == std::string_view::npos) {
                fail("malformed multipart header line: " + std::string(line.substr(0, 80)));
                return false;
            }
            part_.headers.emplace_back(to_lower(trim(line.substr(0, colon))),
                                       std::string(trim(line.substr(colon + 1))));
            return true;
        }
        case State::Body: {
            if (body_length_) {
                if (available < *body_length_ + delimiter_.size()) return false;
                if (buffer_.compare(start_ + *body_length_, delimiter_.size(), delimiter_) != 0) {
                    fail("a multipart part is longer than its Content-Length");
                    return false;
                }
                part_.body = buffer_.substr(start_, *body_length_);
                start_ += *body_length_ + delimiter_.size();
            } else {
                const size_t at = buffer_.find(delimiter_, std::max(start_, search_from_));
                if (at == std::string::npos) {
                    const size_t keep = delimiter_.size() - 1;
                    search_from_ =
                        std::max(start_, buffer_.size() > keep ? buffer_.size() - keep : 0);
                    return false;
                }
                part_.body = buffer_.substr(start_, at - start_);
                start_ = at + delimiter_.size();
            }
            parts.push_back(std::move(part_));
            part_ = MultipartPart();
            state_ = State::AfterDelimiter;
            return true;
        }
        case State::Finished:
        case State::Failed:
            return false;
    }
    return false;
}

}  // namespace photond::client
