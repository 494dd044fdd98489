#include "server/http_thread_pool.h"

#include <algorithm>

namespace photond::service {

HttpThreadPool::HttpThreadPool(size_t max_threads, size_t kept_threads, std::chrono::milliseconds idle_timeout)
    : max_threads_(std::max<size_t>(max_threads, 1)),
      kept_threads_(std::min(kept_threads, max_threads_)),
      idle_timeout_(idle_timeout) {}

HttpThreadPool::~HttpThreadPool() { shutdown(); }

void HttpThreadPool::enqueue(std::function<void()> task) {
    std::lock_guard lock(mutex_);
    join_finished_locked();
    tasks_.push_back(std::move(task));
    // A waiting thread takes it; otherwise one more thread, while the limit allows.
    if (idle_ >= tasks_.size() || threads_.size() >= max_threads_) {
        task_available_.notify_one();
        return;
    }
    threads_.emplace_back();
    const auto self = std::prev(threads_.end());
    *self = std::thread([this, self] { work(self); });
}

void HttpThreadPool::work(std::list<std::thread>::iterator self) {
    std::unique_lock lock(mutex_);
    for (;;) {
        ++idle_;
        const bool woken = task_available_.wait_for(lock, idle_timeout_, [&] { return stopping_ || !tasks_.empty(); });
        --idle_;
        if (!tasks_.empty()) {
            std::function<void()> task = std::move(tasks_.front());
            tasks_.pop_front();
            lock.unlock();
            task();
            task = nullptr;  // the connection's state goes with its task, not with the next wait
            lock.lock();
            continue;
        }
        if (stopping_) return;  // shutdown() joins every thread
        // Idle past the timeout: end, unless this is one of the threads kept for the next burst.
        if (!woken && threads_.size() - finished_.size() > kept_threads_) {
            finished_.push_back(self);
            return;
        }
    }
}

void HttpThreadPool::join_finished_locked() {
    for (auto finished : finished_) {
        finished->join();  // it has returned from work() or is about to: no lock is needed
        threads_.erase(finished);
    }
    finished_.clear();
}

void HttpThreadPool::shutdown() {
    std::list<std::thread> threads;
    {
        std::lock_guard lock(mutex_);
        stopping_ = true;
        finished_.clear();  // joined below with the others
        threads.swap(threads_);
    }
    task_available_.notify_all();
    for (std::thread& thread : threads)
        if (thread.joinable()) thread.join();
}

}  // namespace photond::service
