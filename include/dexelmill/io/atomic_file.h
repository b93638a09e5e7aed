/// @file atomic_file.h
/// @brief Every file the library writes goes through here: the content is written to a
/// temporary file in the target's directory and renamed over the target only once it is
/// complete, so a failed or interrupted run never leaves a half-written or clobbered file.
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
///    a regular file. A write that fails may leave part of the content in it;
///  - a folder or a socket is refused.
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace dexelmill {

/// @brief Calls `write` with the path to write `target`'s content to (see the file comment): a
/// fresh temporary file beside the file `target` leads to (created empty), which is then given the
/// replaced file's mode, flushed to disk and renamed over it; or the device or FIFO itself.
/// If `write` throws, the temporary file is removed and the exception propagates; `target` is
/// untouched.
/// @throw Error if `target` is a folder or a socket, or the temporary file cannot be created,
/// flushed or renamed.
void writeFileAtomically(const std::string& target,
                         const std::function<void(const std::string& path)>& write);

/// @brief Fails now, rather than after a long run, where writeFileAtomically(target) could not
/// start: for a device or FIFO, unless the user may write it; else it creates and removes a
/// temporary file beside the file `target` leads to.
/// @throw Error naming `target` and the reason.
void checkWritable(const std::string& target);

/// @brief writeFileAtomically with a binary std::ostream on the temporary file.
/// @throw Error if the stream fails at any point.
void writeStreamAtomically(const std::string& target,
                           const std::function<void(std::ostream& out)>& write);

}  // namespace dexelmill
