/// @file atomic_file.h
/// @brief Every file the library writes goes through here: the content is written to a
/// temporary file in the target's directory and renamed over the target only once it is
/// complete, so a failed or interrupted run never leaves a half-written or clobbered file; an
/// OutputBatch renames a run's files together, once all are written.
///
/// What the target names decides how it is written, as a careful Unix tool treats its output
/// (GNU `sed -i --follow-symlinks`, `cp` onto an existing file):
///  - a symbolic link is followed to the file its chain of links ends at; that file is written
///    (made, when it is missing, as the shell's `>` makes it) and the link stays a link;
///  - a file that does not exist is made with the permissions a new file gets (0666 less the
///    umask);
///  - an existing regular file is replaced by the new one, which takes its mode (permission,
///    set-ID and sticky bits) and, where the user may set them (root may), its owner and group;
///    other hard links to it keep the old content;
///  - a device or a FIFO (named pipe) is opened and written in place, with no temporary file and
///    no flush to disk: renaming over it would replace `/dev/null` or a pipe's reader's end with
///    a regular file. A write that fails may leave part of the content in it. So is an open
///    descriptor, a path through /proc/PID/fd (`/dev/stdout`, `/dev/fd/N`), whatever it holds: the
///    file, pipe or terminal the shell's redirection set up is written from its start, and stays
///    the descriptor's;
///  - a folder or a socket is refused.
#pragma once

#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace dexelmill {

/// @brief The files one run writes, renamed over their targets together: each is staged in its
/// temporary file, complete and flushed to disk, and commit() renames them all, so that a run that
/// fails at its last file (a full disk while writing the report), or at one of the renames,
/// leaves every target as it was.
/// A batch destroyed before commit() removes its temporary files. A device or FIFO target has no
/// temporary file: it is written when staged.
class OutputBatch {
public:
    OutputBatch() = default;
    OutputBatch(const OutputBatch&) = delete;
    OutputBatch& operator=(const OutputBatch&) = delete;
    /// @brief Removes the temporary files not renamed.
    ~OutputBatch();

    /// @brief Calls `write` with the path to write `target`'s content to (see the file comment):
    /// a fresh temporary file beside the file `target` leads to (created empty), which is then
    /// given the replaced file's mode and flushed to disk, to be renamed by commit(); or the device
    /// or FIFO itself. If `write` throws, its temporary file is removed and the exception
    /// propagates; `target` and the files staged before are untouched.
    /// @throw Error if `target` is a folder or a socket, or the temporary file cannot be created or
    /// flushed.
    void stage(const std::string& target, const std::function<void(const std::string& path)>& write);

    /// @brief Renames every staged temporary file over its target, in the order staged. Until the
    /// last rename is done, each file replaced is kept under a second hard link beside it (a
    /// hidden name ending ".oldPID_N"), which removeLiveTemporaries removes.
    /// @throw Error naming the file whose rename fails (its folder removed meanwhile, say): the
    /// renames before it are undone, each replaced file renamed back over its target (the same
    /// file, other hard links to it untouched) and each target that was new removed, so that
    /// every target is as it was. Where a folder takes no hard link (a file system without them),
    /// a replaced file cannot be put back: the message names the targets that keep the run's
    /// files, and where a backup could not be renamed back, the backup.
    void commit();

private:
    struct Staged {
        std::string temp;    ///< the temporary file
        std::string file;    ///< what it is renamed to: the target with its links followed
        std::string target;  ///< the target as named, for messages
        int slot = -1;       ///< its place in removeLiveTemporaries' table, -1 for none
    };
    std::vector<Staged> staged_;
};

/// @brief Writes `target` through `write` (OutputBatch::stage) and renames it at once; or, given a
/// `batch`, stages it there, to be renamed by the batch's commit().
/// @throw Error as OutputBatch::stage and commit do.
void writeFileAtomically(const std::string& target,
                         const std::function<void(const std::string& path)>& write,
                         OutputBatch* batch = nullptr);

/// @brief Fails now, rather than after a long run, where writeFileAtomically(target) could not
/// start: for a device or FIFO, unless the user may write it; else it creates and removes a
/// temporary file beside the file `target` leads to.
/// @throw Error naming `target` and the reason.
void checkWritable(const std::string& target);

/// @brief Whether `target` is written in place (see the file comment): a device, a FIFO or an open
/// descriptor, whatever its name; such a target takes any content, whatever its extension says.
/// False for any other target, and for one that cannot be examined (which writing then names).
bool writtenInPlace(const std::string& target);

/// @brief Whether the output `target` may be written in the format of `extension` (".json", dot
/// included, lower case): its name ends so, in any case, or it is written in place, which takes
/// any content whatever its name.
bool takesFormat(const std::string& target, const std::string& extension);

/// @brief A file a job reads or writes, and the option (or argument) that names it.
struct NamedFile {
    std::string option;  ///< as the user gives it: "-o", "--report", "INPUTS", "DESIGN", ...
    std::string path;    ///< empty where the option is not given
};

/// @brief Removes every temporary file this process has made and not yet renamed or removed, as
/// a signal handler may: only unlink(2) on paths kept in a fixed table, no allocation, no lock.
/// The table holds kTrackedTemporaries paths; a file made while it is full is not tracked, and
/// would outlive an interruption. Called by the handler removeTemporariesOnSignals installs.
void removeLiveTemporaries() noexcept;

/// The temporary files removeLiveTemporaries can reach at once: a run stages one per output, and
/// keeps one backup per replaced output while it commits.
constexpr int kTrackedTemporaries = 64;

/// @brief Makes SIGINT, SIGTERM and SIGHUP remove the live temporary files
/// (removeLiveTemporaries) before the process ends by the signal as it would have without the
/// handler, so that Ctrl-C during a long write leaves no hidden partial file beside the output.
/// A signal the process started ignoring (nohup, a shell's background job) stays ignored.
void removeTemporariesOnSignals();

/// @brief Fails before a job starts where an output would overwrite one of its inputs or another
/// of its outputs. Two paths name the same file when they reach the same file (the same device
/// and inode, through any links, hard ones too) or, where neither exists yet, the same path once
/// their symbolic links are followed and the path is made absolute (weakly_canonical). Empty
/// paths are not compared, nor two outputs written in place (writtenInPlace): `/dev/null` takes
/// several, one after another.
/// @throw Error naming both options and paths.
void checkSeparateFiles(const std::vector<NamedFile>& inputs, const std::vector<NamedFile>& outputs);

/// @brief writeFileAtomically with a binary std::ostream on the file written.
/// @throw Error if the stream fails at any point.
void writeStreamAtomically(const std::string& target,
                           const std::function<void(std::ostream& out)>& write,
                           OutputBatch* batch = nullptr);

}  // namespace dexelmill
