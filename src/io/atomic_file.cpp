#include "dexelmill/io/atomic_file.h"

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "dexelmill/error.h"
#include "dexelmill/io/file_name.h"

namespace dexelmill {

namespace {

/// The temporary files alive, for removeLiveTemporaries: a slot is free (0), being filled or
/// emptied (1), or holds a path (2). Paths longer than a slot are not tracked.
struct TrackedTemporary {
    std::atomic<int> state{0};
    char path[4096];
};
TrackedTemporary tracked[kTrackedTemporaries];

/// Puts `path` in a free slot of the table; -1 when none is free or the path does not fit.
int track(const std::string& path) {
    if (path.size() >= sizeof(TrackedTemporary::path)) return -1;
    for (int i = 0; i < kTrackedTemporaries; ++i) {
        int free = 0;
        if (!tracked[i].state.compare_exchange_strong(free, 1)) continue;
        std::memcpy(tracked[i].path, path.c_str(), path.size() + 1);
        tracked[i].state.store(2, std::memory_order_release);
        return i;
    }
    return -1;
}

/// Frees the slot of a temporary file that was renamed or removed.
void untrack(int slot) {
    if (slot >= 0) tracked[slot].state.store(0, std::memory_order_release);
}

void removeOnSignal(int signal) {
    removeLiveTemporaries();
    // End as the signal would have ended the process: its default action, raised again.
    std::signal(signal, SIG_DFL);
    std::raise(signal);
}

std::string systemError(const std::string& what, const std::string& path) {
    return what + " '" + path + "': " + std::strerror(errno);
}

/// The longest file name `dir` takes: its file system's NAME_MAX, or 255 where it does not say.
std::size_t longestName(const std::filesystem::path& dir) {
    const long max = ::pathconf(dir.c_str(), _PC_NAME_MAX);
    return max > 0 ? std::size_t(max) : 255;
}

/// "." + `name` + `suffix`, with `name` cut short (at a UTF-8 character's start) where the whole
/// would be longer than `longest` bytes: a temporary file of any name the folder takes is still
/// recognisably the target's.
std::string temporaryName(const std::string& name, const std::string& suffix, std::size_t longest) {
    std::size_t keep = name.size();
    if (1 + keep + suffix.size() > longest) {
        keep = longest > 1 + suffix.size() ? longest - 1 - suffix.size() : 0;
        while (keep > 0 && (static_cast<unsigned char>(name[keep]) & 0xC0) == 0x80) --keep;
    }
    return "." + name.substr(0, keep) + suffix;
}

/// Whether `link` is an entry of a process's table of open files (/proc/PID/fd/N, which
/// /dev/stdout and /dev/fd/N lead to): its text names what the descriptor holds ("pipe:[N]" for
/// a pipe), not always a path.
bool isDescriptorLink(const std::filesystem::path& link) {
    std::error_code ec;
    const std::filesystem::path folder = std::filesystem::canonical(link.parent_path(), ec);
    return !ec && folder.filename() == "fd" && folder.parent_path().parent_path() == "/proc";
}

/// The file `target` ends at: `target` itself, or the file its chain of symbolic links leads to
/// (which need not exist). Each link's text is taken from the link's folder, as the system reads it.
/// `throughDescriptor`, if given, says whether the chain passes through an open file's entry
/// (isDescriptorLink).
/// @throw Error for a link that cannot be read, or a chain as long as the system refuses (ELOOP).
std::filesystem::path followLinks(const std::string& target, bool* throughDescriptor = nullptr) {
    constexpr int kMostLinks = 40;  // Linux's MAXSYMLINKS
    std::filesystem::path file = target;
    if (throughDescriptor) *throughDescriptor = false;
    for (int links = 0;; ++links) {
        std::error_code ec;
        if (!std::filesystem::is_symlink(std::filesystem::symlink_status(file, ec))) return file;
        if (throughDescriptor && isDescriptorLink(file)) *throughDescriptor = true;
        if (links == kMostLinks) throw Error("cannot write '" + target + "': too many levels of symbolic links");
        const std::filesystem::path to = std::filesystem::read_symlink(file, ec);
        if (ec) throw Error("cannot read the link '" + file.string() + "': " + ec.message());
        file = to.is_absolute() ? to : file.parent_path() / to;
    }
}

/// Where and how a target is written (see atomic_file.h).
struct Destination {
    /// The target with its symbolic links followed; the target itself where it is written in place.
    std::filesystem::path file;
    bool inPlace = false;  ///< a device, a FIFO or an open descriptor: opened and written as it is
    /// The regular file the new one replaces, whose owner, group and mode it takes.
    std::optional<struct stat> replaces;
};

Destination destinationOf(const std::string& target) {
    if (target.empty()) throw Error("cannot write a file with an empty name");
    Destination d;
    bool descriptor = false;
    d.file = followLinks(target, &descriptor);
    // What the target is, as the system resolves it: a descriptor's link (/dev/stdout on a pipe)
    // names no path that followLinks could reach.
    struct stat st {};
    if (::stat(target.c_str(), &st) != 0) {
        // A new file; where its folder is missing, the temporary file's creation says so.
        if (errno == ENOENT && !descriptor) return d;
        throw Error(systemError("cannot write", target));
    }
    if (S_ISDIR(st.st_mode)) throw Error("cannot write '" + target + "': it is a folder");
    if (S_ISSOCK(st.st_mode)) throw Error("cannot write '" + target + "': it is a socket");
    if (S_ISREG(st.st_mode) && !descriptor) {
        d.replaces = st;
        return d;
    }
    d.inPlace = true;
    d.file = target;
    return d;
}

/// Creates a new, empty, uniquely named file beside `d.file` and returns its path.
/// Makes something under a fresh hidden name beside `file`: "." + its name + `tag` + "PID_N"
/// (temporaryName), each try calling `make(path)`, which returns whether it made it and otherwise
/// leaves errno set. Tries names until one is made or `make` fails for a reason other than the
/// name being taken (EEXIST). The path made, or empty (errno says why; 0 where every name tried
/// was taken).
template <class Make>
std::string makeBeside(const std::filesystem::path& file, const char* tag, Make&& make) {
    static std::atomic<unsigned> counter{0};
    const std::filesystem::path dir =
        file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
    const std::size_t longest = longestName(dir);
    for (int attempt = 0; attempt < 100; ++attempt) {
        const std::string suffix =
            tag + std::to_string(::getpid()) + "_" + std::to_string(counter.fetch_add(1));
        const std::string path =
            (dir / temporaryName(file.filename().string(), suffix, longest)).string();
        if (make(path)) return path;
        if (errno != EEXIST) return {};
    }
    errno = 0;
    return {};
}

std::string createTemporary(const std::string& target, const Destination& d) {
    // O_EXCL: never reuse a file someone else made. Mode 0666 less the umask, like any new file
    // the user writes; or, replacing a file, no more than its own bits (and read and write for
    // its writer, who reopens it), so that no one may read the content who may not read the file.
    const mode_t mode = d.replaces ? (d.replaces->st_mode & 0777) | 0600 : 0666;
    const std::string path = makeBeside(d.file, ".tmp", [mode](const std::string& p) {
        const int fd = ::open(p.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
        if (fd < 0) return false;
        ::close(fd);
        return true;
    });
    if (!path.empty()) return path;
    if (errno != 0) throw Error(systemError("cannot create a temporary file for", target));
    throw Error("cannot find a free temporary file name for '" + target + "'");
}

/// Gives the written temporary file the owner, group and mode of the file it replaces, as
/// `sed -i` does (the owner and group where the user may set them: root may, others keep their
/// own), and flushes it to disk.
void finishTemporary(const std::string& temp, const Destination& d) {
    const int fd = ::open(temp.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw Error(systemError("cannot reopen", temp));
    if (d.replaces) {
        const struct stat& st = *d.replaces;
        // The owner first: a change of owner clears the set-user-ID bit the mode then restores.
        if (::fchown(fd, st.st_uid, st.st_gid) != 0 && ::fchown(fd, uid_t(-1), st.st_gid) != 0) {
            // Neither may be set: the new file is the user's own, as any file the user makes.
        }
        if (::fchmod(fd, st.st_mode & 07777) != 0) {
            const std::string message = systemError("cannot set the mode of", temp);
            ::close(fd);
            throw Error(message);
        }
    }
    const int rc = ::fsync(fd);
    ::close(fd);
    if (rc != 0) throw Error(systemError("cannot flush", temp));
}

/// A second hard link to the regular file `file`, under a fresh hidden name beside it, which
/// OutputBatch::commit renames back over `file` where a later rename fails; empty where `file` is
/// not a regular file or its folder takes no hard link (a file system without them, a full
/// folder, a file at its most links).
std::string linkBackup(const std::string& file) {
    struct stat st {};
    if (::lstat(file.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return {};
    return makeBeside(file, ".old", [&file](const std::string& p) {
        return ::link(file.c_str(), p.c_str()) == 0;
    });
}

/// Whether two paths name the same file (see checkSeparateFiles).
bool sameFile(const std::string& a, const std::string& b) {
    struct stat sa {}, sb {};
    const int errorA = ::stat(a.c_str(), &sa) == 0 ? 0 : errno;
    const int errorB = ::stat(b.c_str(), &sb) == 0 ? 0 : errno;
    if (errorA == 0 && errorB == 0) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    // A file that exists is not one that does not; a path the system cannot follow (a loop of
    // links, a folder it may not search) names no file to compare, and fails where it is used.
    if (errorA != ENOENT || errorB != ENOENT) return false;
    std::error_code ecA, ecB;
    const std::filesystem::path pathA = std::filesystem::weakly_canonical(followLinks(a), ecA);
    const std::filesystem::path pathB = std::filesystem::weakly_canonical(followLinks(b), ecB);
    return !ecA && !ecB && pathA == pathB;
}

}  // namespace

bool writtenInPlace(const std::string& target) {
    try {
        return destinationOf(target).inPlace;
    } catch (const Error&) {
        return false;
    }
}

bool takesFormat(const std::string& target, const std::string& extension) {
    return lowerExtension(target) == extension || writtenInPlace(target);
}

void checkSeparateFiles(const std::vector<NamedFile>& inputs, const std::vector<NamedFile>& outputs) {
    // Outputs written in place (/dev/null for several) take what they are given, one after another.
    std::vector<bool> inPlace(outputs.size());
    for (std::size_t i = 0; i < outputs.size(); ++i)
        inPlace[i] = !outputs[i].path.empty() && writtenInPlace(outputs[i].path);
    for (std::size_t i = 0; i < outputs.size(); ++i) {
        const NamedFile& out = outputs[i];
        if (out.path.empty()) continue;
        for (const NamedFile& in : inputs)
            if (!in.path.empty() && sameFile(out.path, in.path))
                throw Error(out.option + " '" + out.path + "' is the same file as " + in.option + " '" + in.path +
                            "', which the job reads: give the output another name");
        for (std::size_t j = 0; j < i; ++j)
            if (!outputs[j].path.empty() && !(inPlace[i] && inPlace[j]) && sameFile(out.path, outputs[j].path))
                throw Error(outputs[j].option + " '" + outputs[j].path + "' and " + out.option + " '" + out.path +
                            "' are the same file: give each output a name of its own");
    }
}

void checkWritable(const std::string& target) {
    const Destination d = destinationOf(target);
    if (d.inPlace) {
        if (::access(d.file.c_str(), W_OK) != 0) throw Error(systemError("cannot write", target));
        return;
    }
    std::error_code ec;
    std::filesystem::remove(createTemporary(target, d), ec);
}

OutputBatch::~OutputBatch() {
    std::error_code ignored;
    for (const Staged& s : staged_) {
        std::filesystem::remove(s.temp, ignored);
        untrack(s.slot);
    }
}

void OutputBatch::stage(const std::string& target, const std::function<void(const std::string& path)>& write) {
    const Destination d = destinationOf(target);
    if (d.inPlace) {
        write(d.file.string());
        return;
    }
    Staged s{createTemporary(target, d), d.file.string(), target};
    s.slot = track(s.temp);
    try {
        write(s.temp);
        finishTemporary(s.temp, d);
    } catch (...) {
        std::error_code ignored;
        std::filesystem::remove(s.temp, ignored);
        untrack(s.slot);
        throw;
    }
    staged_.push_back(std::move(s));
}

void OutputBatch::commit() {
    // What puts a renamed target back: the file it replaced, kept under a second hard link
    // (linkBackup) until every rename is done; or, for a target that was not there, removal.
    struct Undo {
        std::string backup;
        int slot = -1;  ///< the backup's place in removeLiveTemporaries' table
        bool existed = false;
    };
    std::vector<Undo> undo;
    undo.reserve(staged_.size());
    const auto dropBackup = [](const Undo& u) {
        if (u.backup.empty()) return;
        ::unlink(u.backup.c_str());
        untrack(u.slot);
    };
    for (std::size_t i = 0; i < staged_.size(); ++i) {
        const Staged& s = staged_[i];
        Undo u;
        struct stat st {};
        u.existed = ::lstat(s.file.c_str(), &st) == 0;
        u.backup = linkBackup(s.file);
        if (!u.backup.empty()) u.slot = track(u.backup);
        std::error_code ec;
        std::filesystem::rename(s.temp, s.file, ec);
        if (!ec) {
            untrack(s.slot);
            undo.push_back(std::move(u));
            continue;
        }
        dropBackup(u);
        std::string message =
            "cannot rename '" + s.temp + "' to '" + s.target + "': " + ec.message();
        // The renames before it undone, last first; a target that cannot be put back keeps the
        // run's file, and the message names it and where the file it replaced is kept.
        std::vector<std::string> kept;
        for (std::size_t j = i; j-- > 0;) {
            std::error_code put;
            if (!undo[j].backup.empty()) {
                std::filesystem::rename(undo[j].backup, staged_[j].file, put);
                if (!put) untrack(undo[j].slot);
            } else if (!undo[j].existed) {
                std::filesystem::remove(staged_[j].file, put);
            } else {
                put = std::make_error_code(std::errc::operation_not_supported);
            }
            if (put) {
                std::string what = "'" + staged_[j].target + "'";
                if (!undo[j].backup.empty()) {
                    untrack(undo[j].slot);  // the old content, for the user to take back
                    what += " (the file it replaced is kept as '" + undo[j].backup + "')";
                }
                kept.push_back(what);
            }
        }
        if (kept.empty()) {
            message += "; no file was changed";
        } else {
            message += "; the run's new content is kept in";
            for (std::size_t k = 0; k < kept.size(); ++k)
                message += (k == 0 ? " " : ", ") + kept[k];
        }
        // The files renamed are gone as temporary files; the destructor removes the rest.
        staged_.erase(staged_.begin(), staged_.begin() + std::ptrdiff_t(i));
        throw Error(message);
    }
    for (const Undo& u : undo) dropBackup(u);
    staged_.clear();
}

void removeLiveTemporaries() noexcept {
    for (TrackedTemporary& t : tracked)
        if (t.state.load(std::memory_order_acquire) == 2) ::unlink(t.path);
}

void removeTemporariesOnSignals() {
    // A signal the process was started ignoring (SIGINT in a shell's background job, SIGHUP under
    // nohup) stays ignored.
    for (const int signal : {SIGINT, SIGTERM, SIGHUP})
        if (std::signal(signal, removeOnSignal) == SIG_IGN) std::signal(signal, SIG_IGN);
}

void writeFileAtomically(const std::string& target, const std::function<void(const std::string& path)>& write,
                         OutputBatch* batch) {
    if (batch) {
        batch->stage(target, write);
        return;
    }
    OutputBatch one;
    one.stage(target, write);
    one.commit();
}

void writeStreamAtomically(const std::string& target, const std::function<void(std::ostream& out)>& write,
                           OutputBatch* batch) {
    writeFileAtomically(target, [&](const std::string& temp) {
        std::ofstream out(temp, std::ios::binary | std::ios::trunc);
        if (!out) throw Error(systemError("cannot open", temp));
        write(out);
        out.flush();
        if (!out) throw Error("writing '" + target + "' failed");
        out.close();
        if (out.fail()) throw Error("writing '" + target + "' failed");
    }, batch);
}

}  // namespace dexelmill
