// Test harness for `photond serve`: the real daemon as a child process on a free loopback port
// with its own cache directory, and a small HTTP/1.1 client over a plain socket.
//
// Why not httplib::Client: the test executables link photond_core and photond_protocol only,
// while cpp-httplib is a compiled library that must be linked with the definitions its Debian
// build used (PkgConfig::HTTPLIB). A 200-line client keeps the tests independent of that, and it
// gives them what a conformance test wants anyway: exact bytes, chunked decoding checked by hand,
// and the power to hang up in the middle of a stream.
#pragma once

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

namespace photond::test {

namespace fs = std::filesystem;
using nlohmann::json;
using Headers = std::vector<std::pair<std::string, std::string>>;

inline const std::string kPhotondBinary = std::string(PHOTOND_BINARY_DIR) + "/server/photond";

inline std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
    return s;
}

/// Reads "Name: value" lines (CRLF or LF) into `headers`, names lower-cased; lines without a
/// colon are skipped.
inline void read_header_lines(std::istream& lines, std::map<std::string, std::string>& headers) {
    std::string line;
    while (std::getline(lines, line)) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        const size_t colon = line.find(':');
        if (colon == std::string::npos) continue;
        std::string value = line.substr(colon + 1);
        value.erase(0, value.find_first_not_of(' '));
        headers[lower(line.substr(0, colon))] = value;
    }
}

inline std::string read_file(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

inline void write_file(const fs::path& path, std::string_view bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// A unique, empty temporary directory, removed with the object.
class TempDir {
public:
    explicit TempDir(const std::string& name) {
        std::random_device random;
        path_ = fs::temp_directory_path() / ("photond_" + name + "_" + std::to_string(::getpid()) +
                                             "_" + std::to_string(random()));
        fs::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ignored;
        fs::remove_all(path_, ignored);
    }
    const fs::path& path() const { return path_; }

private:
    fs::path path_;
};

struct HttpResponse {
    int status = 0;                              // 0: no response (connection failed or timed out)
    std::map<std::string, std::string> headers;  // names lower-cased
    std::string body;

    std::string header(const std::string& name) const {
        const auto it = headers.find(lower(name));
        return it == headers.end() ? std::string() : it->second;
    }
    json json_body() const { return json::parse(body, nullptr, false); }
};

/// Decodes "Transfer-Encoding: chunked" as bytes arrive.
class ChunkedDecoder {
public:
    /// Appends the decoded bytes of `input` to `output`; false on malformed framing.
    bool feed(std::string_view input, std::string& output) {
        buffer_.append(input);
        for (;;) {
            if (finished_) return true;
            if (remaining_ == 0) {
                const size_t line_end = buffer_.find("\r\n", position_);
                if (line_end == std::string::npos) break;
                const std::string line = buffer_.substr(position_, line_end - position_);
                if (expect_crlf_) {
                    if (!line.empty()) return false;  // the CRLF after a chunk's data
                    expect_crlf_ = false;
                    position_ = line_end + 2;
                    continue;
                }
                size_t size = 0;
                try {
                    size = std::stoul(line, nullptr, 16);
                } catch (const std::exception&) {
                    return false;
                }
                position_ = line_end + 2;
                if (size == 0) {
                    finished_ = true;
                    return true;
                }
                remaining_ = size;
            }
            const size_t available = std::min(remaining_, buffer_.size() - position_);
            if (available == 0) break;
            output.append(buffer_, position_, available);
            position_ += available;
            remaining_ -= available;
            if (remaining_ == 0) expect_crlf_ = true;
        }
        buffer_.erase(0, position_);
        position_ = 0;
        return true;
    }
    bool finished() const { return finished_; }

private:
    std::string buffer_;
    size_t position_ = 0;
    size_t remaining_ = 0;
    bool expect_crlf_ = false;
    bool finished_ = false;
};

/// One HTTP/1.1 exchange on its own connection ("Connection: close").
class HttpClient {
public:
    explicit HttpClient(int port, std::string token = {}) : port_(port), token_(std::move(token)) {}

    HttpResponse request(const std::string& method, const std::string& path,
                         std::string_view body = {}, const Headers& headers = {},
                         std::chrono::milliseconds timeout = std::chrono::seconds(60)) const {
        HttpResponse response;
        std::string received;
        stream(method, path, body, headers, timeout, response, [&](std::string_view data) {
            received.append(data);
            return true;
        });
        response.body = std::move(received);
        return response;
    }

    HttpResponse get(const std::string& path, const Headers& headers = {}) const {
        return request("GET", path, {}, headers);
    }
    HttpResponse post(const std::string& path, std::string_view body,
                      const Headers& headers = {}) const {
        return request("POST", path, body, headers);
    }

    /// Sends the request and hands the decoded body to `on_data` as it arrives; when `on_data`
    /// returns false the connection is closed at once (a client hanging up mid-stream). Fills
    /// `response`'s status and headers. Returns false when no complete response head arrived.
    bool stream(const std::string& method, const std::string& path, std::string_view body,
                const Headers& headers, std::chrono::milliseconds timeout, HttpResponse& response,
                const std::function<bool(std::string_view)>& on_data) const {
        const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
        if (fd < 0) return false;
        struct Closer {
            int fd;
            ~Closer() { ::close(fd); }
        } closer{fd};
        timeval tv{static_cast<time_t>(timeout.count() / 1000),
                   static_cast<suseconds_t>((timeout.count() % 1000) * 1000)};
        ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
        ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
        sockaddr_in address{};
        address.sin_family = AF_INET;
        address.sin_port = htons(static_cast<uint16_t>(port_));
        address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        if (::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) return false;

        std::string head = method + " " + path +
                           " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port_) +
                           "\r\nConnection: close\r\n";
        if (!token_.empty()) head += "Authorization: Bearer " + token_ + "\r\n";
        bool has_length = false;
        for (const auto& [name, value] : headers) {
            has_length |= lower(name) == "content-length";
            // {"Content-Length", ""} sends none: a request without a body (RFC 9112, 6.3).
            if (lower(name) == "content-length" && value.empty()) continue;
            head += name + ": " + value + "\r\n";
        }
        if (!has_length && (!body.empty() || method == "POST" || method == "PUT"))
            head += "Content-Length: " + std::to_string(body.size()) + "\r\n";
        head += "\r\n";
        send_all(fd, head);
        // A large body may be refused from its Content-Length alone (413): the server answers and
        // closes without reading it, and a client still sending would get a reset that can
        // swallow the answer. Real clients send "Expect: 100-continue"; this one waits briefly.
        pollfd early{fd, POLLIN, 0};
        if (body.size() <= (size_t{64} << 10) || ::poll(&early, 1, 200) == 0) send_all(fd, body);

        std::string buffer;
        char chunk[65536];
        size_t head_end = std::string::npos;
        while (head_end == std::string::npos) {
            const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
            if (n <= 0) return false;
            buffer.append(chunk, static_cast<size_t>(n));
            head_end = buffer.find("\r\n\r\n");
        }
        parse_head(buffer.substr(0, head_end), response);
        std::string rest = buffer.substr(head_end + 4);
        const bool chunked =
            lower(response.header("transfer-encoding")).find("chunked") != std::string::npos;
        std::optional<size_t> length;
        if (!response.header("content-length").empty())
            length = std::stoul(response.header("content-length"));
        if (method == "HEAD" || response.status == 204 || response.status == 304) length = 0;

        ChunkedDecoder decoder;
        size_t delivered = 0;
        auto deliver = [&](std::string_view data) -> bool {
            if (chunked) {
                std::string decoded;
                if (!decoder.feed(data, decoded))
                    throw std::runtime_error("malformed chunked body");
                return decoded.empty() || on_data(decoded);
            }
            if (length) data = data.substr(0, std::min(data.size(), *length - delivered));
            delivered += data.size();
            return data.empty() || on_data(data);
        };
        auto complete = [&] {
            return chunked ? decoder.finished() : (length && delivered >= *length);
        };
        if (!deliver(rest)) return true;
        while (!complete()) {
            const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
            if (n <= 0) break;
            if (!deliver(std::string_view(chunk, static_cast<size_t>(n)))) return true;
        }
        return true;
    }

private:
    static bool send_all(int fd, std::string_view data) {
        while (!data.empty()) {
            const ssize_t n = ::send(fd, data.data(), data.size(), MSG_NOSIGNAL);
            if (n <= 0) return false;
            data.remove_prefix(static_cast<size_t>(n));
        }
        return true;
    }

    static void parse_head(const std::string& head, HttpResponse& response) {
        std::istringstream lines(head);
        std::string line;
        std::getline(lines, line);
        if (line.size() >= 12) response.status = std::stoi(line.substr(9, 3));
        read_header_lines(lines, response.headers);
    }

    int port_;
    std::string token_;
};

/// One Server-Sent Event.
struct SseEvent {
    uint64_t id = 0;
    std::string type;
    json data;
};

/// Parses complete events out of an SSE text (comments skipped); `consumed` says how much of
/// `text` they used, so that a caller can keep the rest for later.
inline std::vector<SseEvent> parse_sse(std::string_view text, size_t* consumed = nullptr) {
    std::vector<SseEvent> events;
    size_t start = 0;
    for (;;) {
        const size_t end = text.find("\n\n", start);
        if (end == std::string_view::npos) break;
        std::istringstream block{std::string(text.substr(start, end - start))};
        std::string line;
        SseEvent event;
        bool has_data = false;
        while (std::getline(block, line)) {
            if (line.rfind("id: ", 0) == 0) event.id = std::stoull(line.substr(4));
            if (line.rfind("event: ", 0) == 0) event.type = line.substr(7);
            if (line.rfind("data: ", 0) == 0) {
                event.data = json::parse(line.substr(6), nullptr, false);
                has_data = true;
            }
        }
        if (has_data) events.push_back(std::move(event));
        start = end + 2;
    }
    if (consumed) *consumed = start;
    return events;
}

/// Follows a job's SSE stream, calling `on_event` for each event, until the stream ends or
/// `on_event` returns false (the client hangs up). Returns the events seen.
inline std::vector<SseEvent> follow_events(const HttpClient& client, const std::string& id,
                                           const std::function<bool(const SseEvent&)>& on_event = {},
                                           std::chrono::seconds timeout = std::chrono::seconds(120)) {
    std::vector<SseEvent> events;
    std::string pending;
    HttpResponse response;
    client.stream("GET", "/v1/jobs/" + id + "/events", {}, {}, timeout, response, [&](std::string_view data) {
        pending.append(data);
        size_t consumed = 0;
        for (SseEvent& e : parse_sse(pending, &consumed)) {
            events.push_back(e);
            if (on_event && !on_event(e)) return false;
        }
        pending.erase(0, consumed);
        return true;
    });
    return events;
}

struct MultipartPart {
    std::map<std::string, std::string> headers;  // names lower-cased
    std::string body;
};

/// Splits a complete multipart body; `closed` tells whether the closing delimiter was there.
inline std::vector<MultipartPart> parse_multipart(const std::string& body,
                                                  const std::string& boundary,
                                                  bool* closed = nullptr) {
    std::vector<MultipartPart> parts;
    const std::string delimiter = "--" + boundary;
    size_t position = body.find(delimiter);
    if (closed) *closed = false;
    while (position != std::string::npos) {
        position += delimiter.size();
        if (body.compare(position, 2, "--") == 0) {
            if (closed) *closed = true;
            break;
        }
        position += 2;  // CRLF
        const size_t head_end = body.find("\r\n\r\n", position);
        if (head_end == std::string::npos) break;
        MultipartPart part;
        std::istringstream lines(body.substr(position, head_end - position));
        read_header_lines(lines, part.headers);
        const size_t length = std::stoul(part.headers.at("content-length"));
        if (head_end + 4 + length > body.size()) break;
        part.body = body.substr(head_end + 4, length);
        parts.push_back(std::move(part));
        position = body.find(delimiter, head_end + 4 + length);
    }
    return parts;
}

/// `photond serve` as a child process. The constructor waits for its "listening on" line.
class Daemon {
public:
    Daemon(const fs::path& cache_dir, std::vector<std::string> extra_arguments = {},
           const fs::path& working_dir = {}) {
        std::vector<std::string> arguments = {
            kPhotondBinary,     "serve",     "--listen", "127.0.0.1:0", "--cache-dir",
            cache_dir.string(), "--threads", "2"};
        arguments.insert(arguments.end(), extra_arguments.begin(), extra_arguments.end());
        log_path_ = cache_dir.parent_path() / (cache_dir.filename().string() + ".daemon.log");
        int out[2];
        if (::pipe(out) != 0) throw std::runtime_error("pipe");
        pid_ = ::fork();
        if (pid_ == 0) {
            ::dup2(out[1], STDOUT_FILENO);
            const int log = ::open(log_path_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
            ::dup2(log, STDERR_FILENO);
            ::close(out[0]);
            ::close(out[1]);
            if (!working_dir.empty() && ::chdir(working_dir.c_str()) != 0) ::_exit(126);
            std::vector<char*> argv;
            for (std::string& a : arguments) argv.push_back(a.data());
            argv.push_back(nullptr);
            ::execv(argv[0], argv.data());
            ::_exit(127);
        }
        ::close(out[1]);
        stdout_fd_ = out[0];
        // The first line: "listening on http://127.0.0.1:PORT".
        std::string line;
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
        while (line.find('\n') == std::string::npos &&
               std::chrono::steady_clock::now() < deadline) {
            pollfd p{stdout_fd_, POLLIN, 0};
            if (::poll(&p, 1, 200) <= 0) continue;
            char c[256];
            const ssize_t n = ::read(stdout_fd_, c, sizeof c);
            if (n <= 0) break;
            line.append(c, static_cast<size_t>(n));
        }
        first_line_ = line.substr(0, line.find('\n'));
        const std::string prefix = "listening on http://127.0.0.1:";
        if (first_line_.rfind(prefix, 0) == 0) port_ = std::stoi(first_line_.substr(prefix.size()));
    }

    ~Daemon() { stop(); }

    bool started() const { return port_ > 0; }
    /// The daemon's resident set size in kB (/proc/<pid>/status VmRSS); 0 when unknown.
    long resident_kb() const {
        std::ifstream status("/proc/" + std::to_string(pid_) + "/status");
        for (std::string line; std::getline(status, line);)
            if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
        return 0;
    }
    int port() const { return port_; }
    const std::string& first_line() const { return first_line_; }
    std::string log() const { return read_file(log_path_); }
    HttpClient client(const std::string& token = {}) const { return HttpClient(port_, token); }

    /// SIGKILL (what a crash or power loss leaves behind: nothing cleaned up), then waits.
    void kill_hard() {
        if (pid_ <= 0) return;
        ::kill(pid_, SIGKILL);
        int status = 0;
        ::waitpid(pid_, &status, 0);
        pid_ = -1;
        exit_status_ = -1;
        if (stdout_fd_ >= 0) ::close(stdout_fd_);
        stdout_fd_ = -1;
    }

    /// SIGTERM, then waits; returns the exit status (-1 if it had to be killed).
    int stop(std::chrono::seconds patience = std::chrono::seconds(20)) {
        if (pid_ <= 0) return exit_status_;
        ::kill(pid_, SIGTERM);
        const auto deadline = std::chrono::steady_clock::now() + patience;
        int status = 0;
        for (;;) {
            const pid_t done = ::waitpid(pid_, &status, WNOHANG);
            if (done == pid_) {
                exit_status_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
                break;
            }
            if (std::chrono::steady_clock::now() > deadline) {
                ::kill(pid_, SIGKILL);
                ::waitpid(pid_, &status, 0);
                exit_status_ = -1;
                break;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
        pid_ = -1;
        if (stdout_fd_ >= 0) ::close(stdout_fd_);
        stdout_fd_ = -1;
        return exit_status_;
    }

private:
    pid_t pid_ = -1;
    int stdout_fd_ = -1;
    int port_ = 0;
    int exit_status_ = -1;
    std::string first_line_;
    fs::path log_path_;
};

/// Runs a command line through the shell; returns its exit status and output (stdout+stderr).
inline std::pair<int, std::string> run_command(const std::string& command) {
    FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
    std::string output;
    char buffer[4096];
    while (size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
    const int status = ::pclose(pipe);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

/// The path of a program on the PATH (`command -v`); empty when there is none.
inline std::string program_path(const std::string& name) {
    auto [status, output] = run_command("command -v " + name);
    while (!output.empty() && std::isspace(static_cast<unsigned char>(output.back())))
        output.pop_back();
    return status == 0 ? output : std::string();
}

/// Polls GET /v1/jobs/{id} until `done(status)` or the timeout; returns the last status.
inline json wait_for_status(const HttpClient& client, const std::string& id,
                            const std::function<bool(const json&)>& done,
                            std::chrono::milliseconds timeout = std::chrono::seconds(30)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    json status;
    while (std::chrono::steady_clock::now() < deadline) {
        status = client.get("/v1/jobs/" + id).json_body();
        if (done(status)) return status;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return status;
}

inline bool is_terminal_state(const json& status) {
    const std::string state = status.value("state", "");
    return state == "done" || state == "failed" || state == "cancelled";
}

}  // namespace photond::test
