// The threads that serve the daemon's HTTP connections: cpp-httplib hands each accepted
// connection to a task queue, and a connection holds its thread for as long as it lasts (an
// event stream for the whole render, a slow client for as long as it trickles). A fixed pool of
// N threads therefore let N slow or idle clients make every other request wait, /healthz too.
// This pool starts a thread whenever a connection arrives and none is idle, up to `max_threads`
// connections at once, and lets threads beyond `kept_threads` end after `idle_timeout` without
// work. Beyond `max_threads` connections wait for a thread, oldest first.
//
// Include only from .cpp files of the photond_daemon library (httplib.h needs the definitions of
// PkgConfig::HTTPLIB; see server/http_server.h).
#pragma once

#include <httplib.h>

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <list>
#include <mutex>
#include <thread>
#include <vector>

namespace photond::service {

class HttpThreadPool final : public httplib::TaskQueue {
public:
    HttpThreadPool(size_t max_threads, size_t kept_threads, std::chrono::milliseconds idle_timeout);
    ~HttpThreadPool() override;
    HttpThreadPool(const HttpThreadPool&) = delete;
    HttpThreadPool& operator=(const HttpThreadPool&) = delete;

    void enqueue(std::function<void()> task) override;
    /// Runs the queued tasks to their end and joins every thread.
    void shutdown() override;

private:
    void work(std::list<std::thread>::iterator self);
    void join_finished_locked();

    const size_t max_threads_;
    const size_t kept_threads_;
    const std::chrono::milliseconds idle_timeout_;

    std::mutex mutex_;
    std::condition_variable task_available_;
    std::deque<std::function<void()>> tasks_;
    std::list<std::thread> threads_;
    std::vector<std::list<std::thread>::iterator> finished_;  // ended on idle, to be joined
    size_t idle_ = 0;
    bool stopping_ = false;
};

}  // namespace photond::service
