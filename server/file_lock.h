// An exclusive lock between processes on a lock file (flock(2)), so that daemons and render nodes
// sharing a cache directory (an NFS mount in production: Linux maps flock onto NFS locks) build a
// key once: the others wait, then find its file.
#pragma once

#include <filesystem>

namespace photond::service {

class FileLock {
public:
    /// Creates the lock file when missing and waits until this process holds the lock. When the
    /// file cannot be opened or locked (a read-only directory), held() is false and nothing is
    /// locked. Lock files are never removed: removing one would let two holders exist at once.
    explicit FileLock(const std::filesystem::path& path);
    ~FileLock();
    FileLock(const FileLock&) = delete;
    FileLock& operator=(const FileLock&) = delete;

    bool held() const { return fd_ >= 0; }

private:
    int fd_ = -1;
};

}  // namespace photond::service
