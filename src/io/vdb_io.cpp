#include "dexelmill/io/vdb_io.h"

#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <optional>

#include <sys/resource.h>
#include <unistd.h>

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include "dexelmill/error.h"
#include "dexelmill/io/atomic_file.h"
#include "dexelmill/surface/levelset_vdb.h"
#include "detail/child_probe.h"
#include "detail/vdb_frame.h"

namespace dexelmill {

namespace {

/// Writes grids as openvdb::io::File::write does (a random-access file: the grids' offsets in its
/// header), but to a stream of ours: File::write opens its own and never looks at its state, so a
/// full disk left a truncated file that was then renamed over the target. Without `seekable`, as
/// io::Stream writes (no offsets: a pipe cannot go back to write them).
class GridWriter : public openvdb::io::Archive {
public:
    void writeTo(std::ostream& out, const openvdb::GridCPtrVec& grids, bool seekable) const {
        Archive::write(out, grids, seekable);
    }
};

/// The argument that makes a start of this program readVdb's probe: `EXE --dexelmill-vdb-probe FILE`.
constexpr const char* kProbeFlag = "--dexelmill-vdb-probe";

/// Where this process was started as readVdb's probe, reads FILE with OpenVDB and ends, before
/// main runs (glibc passes the functions it runs at start-up the program's arguments): status 0
/// whether the file reads or OpenVDB throws, a signal where it crashes. It writes no core file.
/// Any program that reads a level set links this file, so it serves all of them.
__attribute__((constructor)) void vdbProbe(int argc, char** argv, char**) {
    if (argc != 3 || std::strcmp(argv[1], kProbeFlag) != 0) return;
    const rlimit noCore{0, 0};
    setrlimit(RLIMIT_CORE, &noCore);
    try {
        openvdb::initialize();
        std::ifstream in(argv[2], std::ios::binary);
        in.exceptions(std::ios::failbit | std::ios::badbit);
        openvdb::io::Stream(in, /*delayLoad=*/false);
    } catch (...) {
    }
    _exit(0);
}

/// The most of an OpenVDB message a reader's error repeats: a damaged file's grid or map name
/// may be any length.
constexpr std::size_t kMostMessageBytes = 200;

std::string clipped(const std::string& message) {
    return printable(message.size() <= kMostMessageBytes ? message : message.substr(0, kMostMessageBytes) + "...");
}

/// An OpenVDB exception's message, clipped, without the name of its type ("RuntimeError: "),
/// which tells a user nothing.
std::string openvdbMessage(const openvdb::Exception& e) {
    const std::string message = e.what();
    const std::size_t colon = message.find(": ");
    const bool typed = colon != std::string::npos && colon >= 5 && message.compare(colon - 5, 5, "Error") == 0 &&
                       message.find(' ') > colon;
    return clipped(typed ? message.substr(colon + 2) : message);
}

/// The first grid of `grids` that `wanted` takes; none when no grid does.
template <typename Wanted>
openvdb::GridBase::Ptr findGrid(const openvdb::GridPtrVec& grids, Wanted wanted) {
    for (const openvdb::GridBase::Ptr& g : grids)
        if (g && wanted(*g)) return g;
    return nullptr;
}

}  // namespace

void writeVdb(const std::string& path, const LevelSet& levelSet, OutputBatch* batch) {
    openvdb::FloatGrid::ConstPtr grid = gridOf(levelSet);
    if (!grid) throw Error("cannot write '" + path + "': the level set holds no grid");
    ensureOpenVdbInitialized();
    const bool seekable = !writtenInPlace(path);
    writeStreamAtomically(path, [&](std::ostream& out) {
        try {
            GridWriter().writeTo(out, openvdb::GridCPtrVec{grid}, seekable);
        } catch (const openvdb::Exception& e) {
            throw Error("cannot write '" + path + "': " + openvdbMessage(e));
        }
    }, batch);
}

LevelSet readVdb(const std::string& path, const std::string& gridName) {
    ensureOpenVdbInitialized();
    // Only regular files: a folder reads as nothing, and /dev/zero or a FIFO never ends.
    std::error_code ec;
    const std::filesystem::file_status st = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(st)) throw Error("cannot open '" + path + "': no such file");
    if (!std::filesystem::is_regular_file(st))
        throw Error("'" + path + "' is not a regular file (a folder, device, pipe or socket); a level set is read "
                    "from a .vdb file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot open '" + path + "': " + std::strerror(errno));
    // A read short of what the file's own counts promise throws at once: OpenVDB's parser does not
    // look at the stream's state, and went on with the sizes and names it had not read (a file cut
    // at 3000 of its 45410 bytes allocated 2 GB and printed a 540 MB map name in its error).
    in.exceptions(std::ios::failbit | std::ios::badbit);
    // OpenVDB's reader allocates and fills a name, string or metadata value of whatever length the
    // file gives before it meets the file's end: a damaged length cost up to 4 GB, in the probe and
    // again below. So every length and offset that frames the file is checked against its size first.
    {
        std::ifstream frame(path, std::ios::binary | std::ios::ate);
        const std::streamoff size = frame ? std::streamoff(frame.tellg()) : std::streamoff(-1);
        if (size >= 0)
            if (const std::optional<detail::VdbFramingProblem> problem =
                    detail::vdbFramingProblem(frame, std::uint64_t(size)))
                throw Error(problem->cutShort ? "'" + path + "': not a complete OpenVDB file (" + problem->what + ")"
                                              : "'" + path + "': not a readable OpenVDB file (" + problem->what +
                                                    ": the file is damaged or cut short)");
    }
    // OpenVDB's reader trusts a leaf's compressed data: some damaged bytes there make it write
    // past a buffer and abort the process ("double free or corruption"). So the file is read
    // first by this program started anew as a probe (vdbProbe), where such a crash ends only the
    // probe; the read below then meets only files the reader survives, and every other error with
    // its own message. Starting it costs about what loading OpenVDB does, some 60 ms.
    const detail::ChildEnd probe = detail::runProcess("/proc/self/exe", {kProbeFlag, path});
    if (probe.crashed) {
        const std::string how = probe.signal == SIGKILL ? "was killed, perhaps for want of memory"
                                : probe.signal != 0    ? std::string("crashed (") + strsignal(probe.signal) + ")"
                                                       : "crashed";
        throw Error("'" + path + "': not a readable OpenVDB file (OpenVDB's reader " + how +
                    " on it: the file is damaged)");
    }
    openvdb::GridPtrVecPtr grids;
    try {
        openvdb::io::Stream stream(in, /*delayLoad=*/false);
        grids = stream.getGrids();
    } catch (const std::ios_base::failure&) {
        throw Error("'" + path + "': not a complete OpenVDB file (it ends, or cannot be read, before the grids "
                    "its header announces)");
    } catch (const std::bad_alloc&) {
        // A size read from damaged bytes: not the job's memory running out.
        throw Error("'" + path + "': not a readable OpenVDB file (a size in it asks for more memory than there is: "
                    "the file is damaged)");
    } catch (const openvdb::Exception& e) {
        // Damaged voxel data (a compressed block Blosc cannot expand, say), or a grid this
        // OpenVDB has no reader for.
        throw Error("'" + path + "': not a readable OpenVDB file (OpenVDB: " + openvdbMessage(e) +
                    "; the file is damaged, or holds what this OpenVDB cannot read)");
    }
    openvdb::GridBase::Ptr base;
    if (!gridName.empty()) {
        base = findGrid(*grids, [&](const openvdb::GridBase& g) { return g.getName() == gridName; });
        if (!base) throw Error("'" + path + "' has no grid named '" + gridName + "'");
    } else {
        base = findGrid(*grids, [](const openvdb::GridBase& g) {
            return g.getName() == "stock" && g.isType<openvdb::FloatGrid>();
        });
        if (!base)
            base = findGrid(*grids, [](const openvdb::GridBase& g) {
                return g.isType<openvdb::FloatGrid>() &&
                       (g.getGridClass() == openvdb::GRID_LEVEL_SET || g.getGridClass() == openvdb::GRID_UNKNOWN);
            });
    }
    if (!base) throw Error("'" + path + "' holds no float level-set grid");
    openvdb::FloatGrid::Ptr grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
    if (!grid) throw Error("grid '" + clipped(base->getName()) + "' in '" + path + "' is not a float grid");
    try {
        return levelSetFromGrid(grid);
    } catch (const Error& e) {
        throw Error("'" + path + "': " + e.what());
    }
}

}  // namespace dexelmill
