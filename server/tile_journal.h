// The finished tiles of a running job, kept on disk as they finish, so that a job running when
// the daemon dies (kill -9, power loss) resumes after the restart from its finished tiles instead
// of starting over:
//   <cache-dir>/jobs/<id>/tiles/<x0>-<y0>.tile
// One file per tile: a header (magic, format version, the job's digest, the rectangle), the
// tile's float RGB pixels as the renderer left them (little-endian), layer after layer (the
// beauty pass, then the job's AOVs in its order), then the SHA-256 of all that.
// Each file is written to a temporary name and renamed, so a crash leaves a whole tile or none;
// a file damaged afterwards (a bad disk, a power loss before the data reached it) fails its
// checksum, is moved aside (".damaged") and its tile is rendered again. Since every pixel's
// samples depend only on (seed, pixel, sample), a restored tile holds exactly the bytes the
// renderer would write again, and the resumed image is byte-identical to an uninterrupted one.
//
// The digest ties the files to one job description and one tile format: a tile written for
// another description (or by a daemon with another format) is never read as this job's.
//
// Thread safety: save() and restore() may be called from several render threads at once (for
// different tiles); clear() must not overlap them.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "core/image/image.h"
#include "core/util/expected.h"

namespace photond::service {

class TileJournal {
public:
    /// `directory` is <job dir>/tiles (created on the first save); `job_digest` identifies the
    /// job description (JobSubmission::request_digest).
    TileJournal(std::filesystem::path directory, std::string job_digest);

    /// Keeps the pixels of `rect` of every layer of `frame`.
    Status save(const PixelRect& rect, const ImageLayers& frame) const;

    enum class Restored { Missing, Restored, Damaged };
    /// Copies a tile kept earlier into `rect` of every layer of `frame` (which has the job's
    /// layers). Damaged: the file was unreadable,
    /// failed its checksum or belongs to another job or rectangle; it was moved aside and
    /// `problem` says why.
    Restored restore(const PixelRect& rect, ImageLayers& frame, std::string* problem = nullptr) const;

    /// How many tile files are kept now.
    size_t count() const;
    /// Removes every kept tile (the job ended).
    void clear() const;

    const std::filesystem::path& directory() const { return directory_; }

private:
    std::filesystem::path file_of(const PixelRect& rect) const;

    std::filesystem::path directory_;
    std::string job_digest_;
};

}  // namespace photond::service
