#include "dexelmill/io/atomic_file.h"

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fcntl.h>
#include <unistd.h>

#include "dexelmill/error.h"

namespace dexelmill {

namespace {

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

/// Creates a new, empty, uniquely named file beside `target` and returns its path.
std::string createTemporary(const std::filesystem::path& target) {
    static std::atomic<unsigned> counter{0};
    const std::filesystem::path dir =
        target.has_parent_path() ? target.parent_path() : std::filesystem::path(".");
    const std::size_t longest = longestName(dir);
    for (int attempt = 0; attempt < 100; ++attempt) {
        const std::string name = temporaryName(target.filename().string(),
                                               ".tmp" + std::to_string(::getpid()) + "_" +
                                                   std::to_string(counter.fetch_add(1)),
                                               longest);
        const std::string path = (dir / name).string();
        // O_EXCL: never reuse a file someone else made; mode 0666 less the umask, like any new
        // file the user writes.
        const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd >= 0) {
            ::close(fd);
            return path;
        }
        if (errno != EEXIST) throw Error(systemError("cannot create a temporary file for", target.string()));
    }
    throw Error("cannot find a free temporary file name for '" + target.string() + "'");
}

void syncFile(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw Error(systemError("cannot reopen", path));
    const int rc = ::fsync(fd);
    ::close(fd);
    if (rc != 0) throw Error(systemError("cannot flush", path));
}

}  // namespace

void checkWritable(const std::string& target) {
    if (target.empty()) throw Error("cannot write a file with an empty name");
    std::error_code ec;
    if (std::filesystem::is_directory(target, ec)) throw Error("cannot write '" + target + "': it is a folder");
    const std::string temp = createTemporary(std::filesystem::path(target));
    std::filesystem::remove(temp, ec);
}

void writeFileAtomically(const std::string& target,
                         const std::function<void(const std::string& tempPath)>& write) {
    if (target.empty()) throw Error("cannot write a file with an empty name");
    const std::string temp = createTemporary(std::filesystem::path(target));
    try {
        write(temp);
        syncFile(temp);
        std::error_code ec;
        std::filesystem::rename(temp, target, ec);
        if (ec) throw Error("cannot rename '" + temp + "' to '" + target + "': " + ec.message());
    } catch (...) {
        std::error_code ignored;
        std::filesystem::remove(temp, ignored);
        throw;
    }
}

void writeStreamAtomically(const std::string& target,
                           const std::function<void(std::ostream& out)>& write) {
    writeFileAtomically(target, [&](const std::string& temp) {
        std::ofstream out(temp, std::ios::binary | std::ios::trunc);
        if (!out) throw Error(systemError("cannot open", temp));
        write(out);
        out.flush();
        if (!out) throw Error("writing '" + target + "' failed");
        out.close();
        if (out.fail()) throw Error("writing '" + target + "' failed");
    });
}

}  // namespace dexelmill
