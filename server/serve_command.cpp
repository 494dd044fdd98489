#include "server/serve_command.h"

#include <arpa/inet.h>
#include <signal.h>
#include <sys/resource.h>

#include <atomic>
#include <cctype>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>

#include "core/accel/ray_tracer.h"
#include "server/http_server.h"
#include "server/job_manager.h"
#include "server/metrics.h"
#include "server/photon_map_cache.h"
#include "protocol/token_file.h"
#include "server/render_cache_directory.h"
#include "server/scene_store.h"

namespace photond::service {
namespace {

namespace fs = std::filesystem;

constexpr const char* kUsage =
    "usage: photond serve [options]\n"
    "  --listen HOST:PORT      address to listen on (default 127.0.0.1:8080; port 0 picks a free\n"
    "                          port); the first line on stdout is \"listening on "
    "http://HOST:PORT\"\n"
    "  --threads N             render threads (default: every core)\n"
    "  --cache-dir DIR         photon maps, render caches, uploaded scenes and job results\n"
    "                          (default: $XDG_CACHE_HOME/photond or ~/.cache/photond)\n"
    "  --photon-cache-mb N     memory for photon maps, least recently used dropped first\n"
    "                          (default 1024; the maps stay on disk)\n"
    "  --render-cache-mb N     memory for irradiance caches (render caches) by view, least\n"
    "                          recently used dropped first (default 256; they stay on disk)\n"
    "  --max-queued N          queued jobs beyond this are refused with 429 (default 64)\n"
    "  --finished-jobs-in-memory N\n"
    "                          finished jobs whose whole record stays in memory, the most\n"
    "                          recently used (default 64); the others are read back from the\n"
    "                          cache directory when asked for\n"
    "  --token-file FILE       clients must send 'Authorization: Bearer <the file's content>';\n"
    "                          required to listen on an address other than loopback\n"
    "  --scene-root DIR        the only directory {\"path\": ...} scenes may be read from\n"
    "                          (default: the current directory)\n"
    "  --max-body-mb N         largest request body, e.g. a scene upload (default 256)\n"
    "  --min-free-mb N         /readyz answers 503 while the cache directory's disk has less free\n"
    "                          (default 64)\n"
    "  --max-bundle-mb N       largest unpacked size of an uploaded zip/tar scene bundle\n"
    "                          (default 1024)\n"
    "  --max-bundle-entries N  most entries of an uploaded scene bundle (default 4096)\n"
    "  --http-threads N        connections served at once, a thread each, started as they\n"
    "                          arrive (default 1024); beyond it connections wait\n"
    "  --access-log            log every request on stderr\n"
    "Stops cleanly on SIGINT or SIGTERM: the running job is interrupted and runs again on the "
    "next\n"
    "start; finished jobs stay fetchable from the cache directory.\n";

struct Arguments {
    std::string host = "127.0.0.1";
    int port = 8080;
    int threads = 0;
    fs::path cache_dir;
    size_t photon_cache_mb = 1024;
    size_t render_cache_mb = 256;
    size_t max_queued = 64;
    size_t finished_jobs_in_memory = 64;
    fs::path token_file;
    fs::path scene_root;
    size_t max_body_mb = 256;
    uint64_t min_free_mb = 64;
    BundleLimits bundle_limits;
    int http_threads = 1024;
    bool access_log = false;
};

template <class T>
Expected<T> parse_count(const std::string& flag, const std::string& text, T min, T max) {
    T value{};
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (error != std::errc() || end != text.data() + text.size() || value < min || value > max)
        return Error{flag + ": expected an integer in [" + std::to_string(min) + ", " +
                     std::to_string(max) + "], got '" + text + "'"};
    return value;
}

/// "HOST:PORT", "[V6]:PORT" or ":PORT" (loopback).
Status parse_listen(const std::string& text, Arguments& a) {
    std::string host, port;
    if (!text.empty() && text[0] == '[') {
        const size_t close = text.find(']');
        if (close == std::string::npos || close + 1 >= text.size() || text[close + 1] != ':')
            return Error{"--listen: expected [IPv6]:PORT, got '" + text + "'"};
        host = text.substr(1, close - 1);
        port = text.substr(close + 2);
    } else {
        const size_t colon = text.rfind(':');
        if (colon == std::string::npos)
            return Error{"--listen: expected HOST:PORT, got '" + text + "'"};
        host = text.substr(0, colon);
        port = text.substr(colon + 1);
    }
    auto number = parse_count<int>("--listen port", port, 0, 65535);
    if (!number) return number.error();
    a.host = host.empty() ? "127.0.0.1" : host;
    a.port = *number;
    return Status::ok();
}

Expected<Arguments> parse_arguments(std::span<const std::string> args) {
    Arguments a;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& arg = args[i];
        auto value = [&]() -> Expected<std::string> {
            if (i + 1 >= args.size()) return Error{arg + ": missing value"};
            return args[++i];
        };
        auto v = arg == "--access-log" ? Expected<std::string>(std::string()) : value();
        if (!v) return v.error();
        if (arg == "--listen") {
            if (Status s = parse_listen(*v, a); !s) return s.error();
        } else if (arg == "--threads") {
            auto n = parse_count<int>(arg, *v, 0, 4096);
            if (!n) return n.error();
            a.threads = *n;
        } else if (arg == "--cache-dir") {
            a.cache_dir = *v;
        } else if (arg == "--render-cache-mb") {
            auto n = parse_count<size_t>(arg, *v, 0, size_t{1} << 24);
            if (!n) return n.error();
            a.render_cache_mb = *n;
        } else if (arg == "--photon-cache-mb") {
            auto n = parse_count<size_t>(arg, *v, 0, size_t{1} << 24);
            if (!n) return n.error();
            a.photon_cache_mb = *n;
        } else if (arg == "--max-queued") {
            auto n = parse_count<size_t>(arg, *v, 1, 1'000'000);
            if (!n) return n.error();
            a.max_queued = *n;
        } else if (arg == "--finished-jobs-in-memory") {
            auto n = parse_count<size_t>(arg, *v, 1, 1'000'000);
            if (!n) return n.error();
            a.finished_jobs_in_memory = *n;
        } else if (arg == "--token-file") {
            a.token_file = *v;
        } else if (arg == "--scene-root") {
            a.scene_root = *v;
        } else if (arg == "--max-body-mb") {
            auto n = parse_count<size_t>(arg, *v, 1, size_t{1} << 20);
            if (!n) return n.error();
            a.max_body_mb = *n;
        } else if (arg == "--min-free-mb") {
            auto n = parse_count<uint64_t>(arg, *v, 0, uint64_t{1} << 40);
            if (!n) return n.error();
            a.min_free_mb = *n;
        } else if (arg == "--max-bundle-mb") {
            auto n = parse_count<uint64_t>(arg, *v, 1, uint64_t{1} << 24);
            if (!n) return n.error();
            a.bundle_limits.max_unpacked_bytes = *n << 20;
        } else if (arg == "--max-bundle-entries") {
            auto n = parse_count<uint64_t>(arg, *v, 1, 100'000'000);
            if (!n) return n.error();
            a.bundle_limits.max_entries = *n;
        } else if (arg == "--http-threads") {
            auto n = parse_count<int>(arg, *v, 4, 4096);
            if (!n) return n.error();
            a.http_threads = *n;
        } else if (arg == "--access-log") {
            a.access_log = true;
        } else {
            return Error{"unknown option '" + arg + "'"};
        }
    }
    return a;
}

fs::path default_cache_dir() {
    if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
        return fs::path(xdg) / "photond";
    if (const char* home = std::getenv("HOME"); home && *home)
        return fs::path(home) / ".cache" / "photond";
    return fs::temp_directory_path() / "photond-cache";
}

bool is_loopback(const std::string& host) {
    if (host == "localhost") return true;
    in_addr v4{};
    if (inet_pton(AF_INET, host.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
    in6_addr v6{};
    if (inet_pton(AF_INET6, host.c_str(), &v6) == 1) return IN6_IS_ADDR_LOOPBACK(&v6);
    return false;  // a host name: it may resolve to anything
}

/// Timestamped lines on stderr, one call at a time.
void log_line(const std::string& line) {
    static std::mutex mutex;
    const std::time_t now = std::time(nullptr);
    std::tm utc{};
    gmtime_r(&now, &utc);
    char stamp[32];
    std::strftime(stamp, sizeof stamp, "%Y-%m-%dT%H:%M:%SZ", &utc);
    std::lock_guard lock(mutex);
    std::fprintf(stderr, "%s photond: %s\n", stamp, line.c_str());
    std::fflush(stderr);
}

}  // namespace

int run_serve_command(std::span<const std::string> args) {
    for (const std::string& a : args) {
        if (a == "-h" || a == "--help") {
            std::fputs(kUsage, stdout);
            return 0;
        }
    }
    auto parsed = parse_arguments(args);
    if (!parsed) {
        std::fprintf(stderr, "photond serve: %s\n%s", parsed.error().message.c_str(), kUsage);
        return 2;
    }
    Arguments& a = *parsed;

    std::string token;
    if (!a.token_file.empty()) {
        auto read = protocol::read_token_file(a.token_file);
        if (!read) {
            std::fprintf(stderr, "photond serve: --token-file %s\n", read.error().message.c_str());
            return 2;
        }
        token = std::move(read).value();
    }
    if (token.empty() && !is_loopback(a.host)) {
        std::fprintf(
            stderr,
            "photond serve: refusing to listen on %s without --token-file: anyone who can reach "
            "that address could submit jobs and read results. Give --token-file FILE (clients "
            "then send 'Authorization: Bearer <token>'), or listen on 127.0.0.1.\n",
            a.host.c_str());
        return 2;
    }
    if (a.cache_dir.empty()) a.cache_dir = default_cache_dir();
    if (a.scene_root.empty()) a.scene_root = fs::current_path();
    std::error_code error;
    fs::create_directories(a.cache_dir, error);
    if (error || !fs::is_directory(a.cache_dir)) {
        std::fprintf(stderr, "photond serve: --cache-dir %s cannot be created%s%s\n",
                     a.cache_dir.string().c_str(), error ? ": " : "",
                     error ? error.message().c_str() : "");
        return 1;
    }
    if (!fs::is_directory(a.scene_root, error)) {
        std::fprintf(stderr, "photond serve: --scene-root %s is not a directory\n",
                     a.scene_root.string().c_str());
        return 1;
    }

    // Signals are taken by sigtimedwait below; every thread started from here on inherits the mask.
    sigset_t stop_signals;
    sigemptyset(&stop_signals);
    sigaddset(&stop_signals, SIGINT);
    sigaddset(&stop_signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
    signal(SIGPIPE, SIG_IGN);  // a client that hangs up mid-stream is a failed write, not a death
    // Each connection is a descriptor: the usual soft limit of 1024 would refuse connections
    // well before --http-threads of them are open.
    if (rlimit files{}; getrlimit(RLIMIT_NOFILE, &files) == 0 && files.rlim_cur < files.rlim_max) {
        files.rlim_cur = std::min<rlim_t>(files.rlim_max, rlim_t{65536});
        setrlimit(RLIMIT_NOFILE, &files);
    }

    auto device = EmbreeDevice::create();
    if (!device) {
        std::fprintf(stderr, "photond serve: %s\n", device.error().message.c_str());
        return 1;
    }
    Metrics metrics;
    PhotonMapCache photon_maps(a.cache_dir / "photon-maps", a.photon_cache_mb << 20, log_line);
    RenderCacheDirectory render_caches(a.cache_dir / "render-caches", a.render_cache_mb << 20, log_line);
    SceneStore scenes(a.cache_dir / "scenes", a.bundle_limits);
    JobManagerOptions job_options;
    job_options.cache_dir = a.cache_dir;
    job_options.scene_root = a.scene_root;
    job_options.threads = a.threads;
    job_options.max_queued = a.max_queued;
    job_options.finished_jobs_in_memory = a.finished_jobs_in_memory;
    job_options.render_caches = &render_caches;
    job_options.log = log_line;
    JobManager jobs(job_options, *device, &photon_maps, &scenes, &metrics);

    HttpServerOptions http_options;
    http_options.host = a.host;
    http_options.port = a.port;
    http_options.token = token;
    http_options.max_body_bytes = a.max_body_mb << 20;
    http_options.min_free_bytes = a.min_free_mb << 20;
    http_options.http_threads = a.http_threads;
    http_options.access_log = a.access_log;
    http_options.log = log_line;
    HttpServer server(http_options, {jobs, scenes, photon_maps, metrics, &render_caches});
    auto port = server.bind();
    if (!port) {
        std::fprintf(stderr, "photond serve: %s\n", port.error().message.c_str());
        return 1;
    }
    jobs.start();

    const std::string host = a.host.find(':') != std::string::npos ? "[" + a.host + "]" : a.host;
    std::printf("listening on http://%s:%d\n", host.c_str(), *port);
    std::fflush(stdout);
    log_line("serving on http://" + host + ":" + std::to_string(*port) + ", cache " +
             a.cache_dir.string() + ", scene root " + a.scene_root.string() +
             (token.empty() ? "" : ", bearer token required"));

    std::atomic<bool> server_ended{false};
    std::thread http([&] {
        server.serve();
        server_ended = true;
    });
    int signal_number = 0;
    while (!server_ended) {
        const timespec interval{1, 0};
        signal_number = sigtimedwait(&stop_signals, nullptr, &interval);
        if (signal_number > 0) break;
    }
    log_line(signal_number > 0 ? std::string("shutting down (") + strsignal(signal_number) + ")"
                               : std::string("the HTTP server stopped; shutting down"));
    // First the jobs: the render stops at its next tile, its state is written, and every waiting
    // stream wakes up and ends; then the HTTP server, whose worker threads can now be joined.
    jobs.shutdown();
    server.stop();
    http.join();
    log_line("stopped");
    return server_ended && signal_number <= 0 ? 1 : 0;
}

}  // namespace photond::service
