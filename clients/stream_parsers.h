// Incremental parsers for the daemon's two streams: Server-Sent Events (GET /v1/jobs/{id}/events)
// and multipart/mixed tile streams (GET /v1/jobs/{id}/tiles). An HTTP client hands over the
// body in whatever pieces the socket delivers; those pieces do not line up with the server's
// events or parts, so both parsers keep a byte buffer and emit only complete items.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace photond::client {

/// One dispatched Server-Sent Event (WHATWG HTML, "Server-sent events", section 9.2.6).
struct SseEvent {
    std::string type = "message";  ///< The `event:` field, "message" when absent.
    std::string data;              ///< `data:` lines joined with '\n'.
    std::string id;                ///< The last event id seen so far in the stream.
    std::optional<int> retry_ms;   ///< The `retry:` field of this event, when present.
};

/// Parses an SSE byte stream. Lines may end in CRLF, LF or CR; comments (":...") are skipped.
/// An event is dispatched at a blank line when it has data or an explicit `event:` type (the
/// standard drops events without data; the daemon's `done` must not be lost to that rule).
class SseParser {
public:
    /// Consumes `bytes` and appends every event completed by them to `events`.
    void feed(std::string_view bytes, std::vector<SseEvent>& events);

    /// The id of the last event that carried one: what a reconnect sends as Last-Event-ID.
    const std::string& last_event_id() const { return last_event_id_; }

private:
    void process_line(std::string_view line, std::vector<SseEvent>& events);

    std::string buffer_;
    std::string data_;
    std::string type_;
    std::optional<int> retry_ms_;
    bool has_data_ = false;
    bool skip_line_feed_ = false;  // the last piece ended in CR: a LF starting the next is its pair
    std::string last_event_id_;
};

/// One body part of a multipart stream with its headers (names lower-cased).
struct MultipartPart {
    std::vector<std::pair<std::string, std::string>> headers;
    std::string body;

    /// The value of header `name` (case-insensitive), or an empty string.
    std::string header(std::string_view name) const;
};

/// The boundary parameter of a multipart Content-Type ("multipart/mixed; boundary=x" or with a
/// quoted value); nullopt when the type is not multipart or has no boundary.
std::optional<std::string> multipart_boundary(std::string_view content_type);

/// Parses a multipart body (RFC 2046 section 5.1.1) as it arrives. A part with a Content-Length
/// header is cut at that length; otherwise at the next CRLF "--boundary" delimiter.
class MultipartParser {
public:
    explicit MultipartParser(std::string boundary);

    /// Consumes `bytes` and appends every part completed by them to `parts`. Returns false once
    /// the stream is malformed (then `error()` says why); later calls do nothing.
    bool feed(std::string_view bytes, std::vector<MultipartPart>& parts);

    /// True after the closing delimiter "--boundary--".
    bool finished() const { return state_ == State::Finished; }
    const std::string& error() const { return error_; }

private:
    enum class State { Preamble, AfterDelimiter, Headers, Body, Finished, Failed };

    bool step(std::vector<MultipartPart>& parts);
    void fail(std::string message);

    std::string delimiter_;  // "\r\n--" + boundary
    std::string buffer_;
    size_t start_ = 0;        // bytes of buffer_ already consumed
    size_t search_from_ = 0;  // where the next delimiter search resumes
    State state_ = State::Preamble;
    MultipartPart part_;
    std::optional<size_t> body_length_;
    std::string error_;
};

}  // namespace photond::client
