#include <catch2/catch.hpp>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <utility>

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include "dexelmill/io/vdb_io.h"
#include "dexelmill/surface/levelset.h"
#include "dexelmill/surface/levelset_vdb.h"
#include "dexelmill/surface/voxelize.h"
#include "io/detail/vdb_frame.h"
#include "support/analytic_parts.h"
#include "support/scratch.h"
#include "support/temp_dir.h"

extern char** environ;

using namespace dexelmill;
using testing::slurp;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
namespace fs = std::filesystem;

namespace {

/// The length a damaged field is given: some 4 GB, the most a uint32 length can ask OpenVDB for.
constexpr std::uint32_t kHugeLength = 0xfffffff0u;
/// An int64 offset far past any file.
constexpr std::int64_t kHugeOffset = std::int64_t(1) << 62;
/// The most resident memory `dexelmill info` may take on a damaged file: it takes some 40 MB on
/// a good one; a damaged length filled would take 4 GB.
constexpr long kMostPeakKiB = 256 * 1024;

void spill(const fs::path& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
}

std::uint32_t getU32(const std::string& bytes, std::size_t at) {
    std::uint32_t v = 0;
    std::memcpy(&v, bytes.data() + at, sizeof v);  // little-endian, as OpenVDB writes on x86
    return v;
}

std::int64_t getI64(const std::string& bytes, std::size_t at) {
    std::int64_t v = 0;
    std::memcpy(&v, bytes.data() + at, sizeof v);
    return v;
}

template <typename T>
std::string with(std::string bytes, std::size_t at, T value) {
    std::memcpy(&bytes[at], &value, sizeof value);
    return bytes;
}

/// Where the uint32 length of the first string `text` stored in `bytes` from byte `from` on (the
/// length, then the characters) begins.
std::size_t lengthOf(const std::string& bytes, const std::string& text, std::size_t from = 0) {
    std::string stored(4, '\0');
    const std::uint32_t n = std::uint32_t(text.size());
    std::memcpy(&stored[0], &n, sizeof n);
    const std::size_t at = bytes.find(stored + text, from);
    REQUIRE(at != std::string::npos);
    return at;
}

/// The level set of a small dented box.
LevelSet dentedBox() {
    TriDexelStock stock = TriDexelStock::fromBox(Box{Vec3(0.0), Vec3(12.0, 10.0, 8.0)}, 0.5);
    testing::carve(stock, testing::sphere(Vec3(6.0, 5.0, 11.0), 5.0));
    return rebuildLevelSet(stock, {3, FamilySet::all(), "dented box", std::nullopt});
}

/// The file metadata written with the grids: a value of each type OpenVDB registers.
openvdb::MetaMap fileMetadata() {
    openvdb::MetaMap meta;
    meta.insertMeta("note_string", openvdb::StringMetadata("a note"));
    meta.insertMeta("note_bool", openvdb::BoolMetadata(true));
    meta.insertMeta("note_int32", openvdb::Int32Metadata(-7));
    meta.insertMeta("note_int64", openvdb::Int64Metadata(-8));
    meta.insertMeta("note_float", openvdb::FloatMetadata(0.5f));
    meta.insertMeta("note_double", openvdb::DoubleMetadata(0.25));
    meta.insertMeta("note_vec2i", openvdb::Vec2IMetadata(openvdb::Vec2i(1, 2)));
    meta.insertMeta("note_vec2s", openvdb::Vec2SMetadata(openvdb::Vec2s(1, 2)));
    meta.insertMeta("note_vec2d", openvdb::Vec2DMetadata(openvdb::Vec2d(1, 2)));
    meta.insertMeta("note_vec3i", openvdb::Vec3IMetadata(openvdb::Vec3i(1, 2, 3)));
    meta.insertMeta("note_vec3s", openvdb::Vec3SMetadata(openvdb::Vec3s(1, 2, 3)));
    meta.insertMeta("note_vec3d", openvdb::Vec3DMetadata(openvdb::Vec3d(1, 2, 3)));
    meta.insertMeta("note_vec4i", openvdb::Vec4IMetadata(openvdb::Vec4i(1, 2, 3, 4)));
    meta.insertMeta("note_vec4s", openvdb::Vec4SMetadata(openvdb::Vec4s(1, 2, 3, 4)));
    meta.insertMeta("note_vec4d", openvdb::Vec4DMetadata(openvdb::Vec4d(1, 2, 3, 4)));
    meta.insertMeta("note_mat4s", openvdb::Mat4SMetadata(openvdb::Mat4s::identity()));
    meta.insertMeta("note_mat4d", openvdb::Mat4DMetadata(openvdb::Mat4d::identity()));
    return meta;
}

/// Two grids, an empty one named "extra" and then the level set's: a file of them needs the
/// first grid's end offset to find the second.
openvdb::GridCPtrVec twoGrids(const LevelSet& ls) {
    openvdb::FloatGrid::Ptr extra = openvdb::FloatGrid::create(1.0f);
    extra->setName("extra");
    return {extra, gridOf(ls)};
}

/// Writes the grids and file metadata with OpenVDB's own random-access writer (grid offsets).
void writeWithOffsets(const fs::path& path, const LevelSet& ls) {
    openvdb::io::File(path.string()).write(twoGrids(ls), fileMetadata());
}

/// Writes them with OpenVDB's stream writer: no grid offsets, as to a pipe.
void writeWithoutOffsets(const fs::path& path, const LevelSet& ls) {
    std::ofstream out(path, std::ios::binary);
    openvdb::io::Stream(out).write(twoGrids(ls), fileMetadata());
}

/// The peak resident memory, in KiB, of `dexelmill info PATH` (with its child dexelmill-core).
long peakKiBOfInfo(const fs::path& path) {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
    const std::string exe = DEXELMILL_CLI_PATH, info = "info", file = path.string();
    char* argv[] = {const_cast<char*>(exe.c_str()), const_cast<char*>(info.c_str()), const_cast<char*>(file.c_str()),
                    nullptr};
    pid_t pid = 0;
    const int spawned = posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv, environ);
    posix_spawn_file_actions_destroy(&actions);
    REQUIRE(spawned == 0);
    int status = 0;
    rusage usage{};
    REQUIRE(::wait4(pid, &status, 0, &usage) == pid);
    CHECK(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 1);
    return usage.ru_maxrss;
}

/// Writes `bytes` as PATH and checks that reading it is refused with a message that starts with
/// `start` and holds `holds`, and that `dexelmill info` refuses it without a large allocation.
void checkRefused(const fs::path& path, const std::string& bytes, const std::string& start, const std::string& holds) {
    spill(path, bytes);
    CHECK_THROWS_WITH(readVdb(path.string()), StartsWith("'" + path.string() + "': " + start) && Contains(holds));
    CHECK(peakKiBOfInfo(path) < kMostPeakKiB);
}

}  // namespace

TEST_CASE("VDB: files OpenVDB writes with file metadata, two grids or no offsets read", "[io]") {
    const fs::path dir = testing::scratchFolder("dexelmill_vdb_frame_", "good");
    const LevelSet ls = dentedBox();
    writeWithOffsets(dir / "offsets.vdb", ls);
    writeWithoutOffsets(dir / "stream.vdb", ls);
    for (const char* name : {"offsets.vdb", "stream.vdb"}) {
        INFO(name);
        const LevelSet back = readVdb((dir / name).string());
        CHECK(back.activeVoxelCount() == ls.activeVoxelCount());
        CHECK(back.source() == "dented box");
    }
}

TEST_CASE("VDB: grids of few leaves, whose delayed-load arrays OpenVDB stores raw or pads, pass the check", "[io]") {
    // OpenVDB stores an array of 48 bytes or fewer raw and pads a longer one under 128 bytes to
    // 128 before Blosc compresses it; the mask takes a byte a leaf and the compressed sizes 8. So
    // the sizes are raw up to 6 leaves and padded from 7 to 15, the mask raw up to 48 and padded
    // from 49 to 127. (A level set of 8 leaves that dexelmill wrote was refused before.)
    openvdb::initialize();
    const fs::path dir = testing::scratchFolder("dexelmill_vdb_frame_", "few");
    for (const int leaves : {1, 6, 7, 8, 15, 16, 48, 49, 100, 127, 128, 300}) {
        INFO(leaves << " leaves");
        openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0.0f);
        for (int i = 0; i < leaves; ++i) grid->tree().setValue(openvdb::Coord(8 * i, 0, 0), 1.0f);
        REQUIRE(grid->tree().leafCount() == openvdb::Index32(leaves));
        const fs::path path = dir / ("leaves" + std::to_string(leaves) + ".vdb");
        openvdb::io::File(path.string()).write({grid});
        const std::string bytes = slurp(path);
        REQUIRE(bytes.find("__delayedload") != std::string::npos);  // the arrays are there
        // OpenVDB reads the file back whole: it is good.
        openvdb::io::File back(path.string());
        back.open();
        CHECK(back.readGrid(grid->getName())->baseTree().leafCount() == openvdb::Index32(leaves));
        back.close();
        std::ifstream in(path, std::ios::binary);
        const std::optional<detail::VdbFramingProblem> problem = detail::vdbFramingProblem(in, bytes.size());
        CHECK((problem ? problem->what : std::string()).empty());
    }
}

TEST_CASE("VDB: a file relabelled as format 222 or 223 reads as format 224", "[io]") {
    // The framing checked before OpenVDB reads a file is the same in these versions: OpenVDB reads
    // a 224 file relabelled so to the same level set. (Relabelled 221, it fails: that format kept
    // a compression byte in the header.)
    const fs::path dir = testing::scratchFolder("dexelmill_vdb_frame_", "versions");
    const LevelSet ls = dentedBox();
    writeVdb((dir / "part.vdb").string(), ls);
    const std::string bytes = slurp(dir / "part.vdb");
    REQUIRE(getU32(bytes, 8) == 224);  // after the int64 magic number
    for (const std::uint32_t version : {222u, 223u}) {
        INFO("format " << version);
        spill(dir / "relabelled.vdb", with(bytes, 8, version));
        CHECK(readVdb((dir / "relabelled.vdb").string()).activeVoxelCount() == ls.activeVoxelCount());
    }
}

TEST_CASE("VDB: a damaged length or offset in the framing is refused before OpenVDB reads it", "[io][errors]") {
    // OpenVDB's reader allocated and filled each length below (some 4 GB) before the file's end
    // refused it, in the probe process and again in the read. Each field's byte offset is found
    // here from the strings OpenVDB stored.
    const fs::path dir = testing::scratchFolder("dexelmill_vdb_frame_", "damaged");
    const LevelSet ls = dentedBox();
    writeWithOffsets(dir / "good.vdb", ls);
    const std::string good = slurp(dir / "good.vdb");
    const fs::path path = dir / "damaged.vdb";
    const std::string readable = "not a readable OpenVDB file (";
    const std::string huge = std::to_string(kHugeLength);

    SECTION("the file metadata's name, type name and value lengths") {
        const std::size_t name = lengthOf(good, "note_string");
        const std::size_t type = name + 4 + std::strlen("note_string");
        REQUIRE(getU32(good, type) == std::strlen("string"));
        const std::size_t value = type + 4 + std::strlen("string");
        REQUIRE(getU32(good, value) == std::strlen("a note"));
        for (const std::size_t at : {name, type, value}) {
            INFO("the length at byte " << at);
            checkRefused(path, with(good, at, kHugeLength), readable + "the length " + huge,
                         "of the file's metadata, at byte " + std::to_string(at) + ", is more than");
        }
    }
    SECTION("a fixed-size value's length, which OpenVDB does not use") {
        // OpenVDB reads a value of a fixed-size type whole whatever length the file gives it.
        const std::size_t value = lengthOf(good, "note_vec3d") + 4 + std::strlen("note_vec3d") + 4 + 5;
        REQUIRE(getU32(good, value) == 24);  // three doubles
        spill(path, with(good, value, kHugeLength));
        CHECK(readVdb(path.string()).activeVoxelCount() == ls.activeVoxelCount());
    }
    // The grids in order: "extra" and then the level set, "stock".
    const std::size_t stock = lengthOf(good, "stock");
    SECTION("a grid descriptor's name and type name lengths") {
        const std::size_t type = lengthOf(good, "Tree_float_5_4_3", stock);
        for (const auto& [at, grid] : {std::pair{lengthOf(good, "extra"), "grid 1"}, std::pair{stock, "grid 2"},
                                       std::pair{type, "grid 2"}}) {
            INFO("the length at byte " << at);
            checkRefused(path, with(good, at, kHugeLength), readable + "the length " + huge,
                         std::string("of ") + grid + ", at byte " + std::to_string(at) + ", is more than");
        }
    }
    SECTION("a grid's block and end offsets") {
        // The level set's descriptor: its name, type name and an empty instance parent's name, then
        // the int64 offsets of the grid, its blocks and its end. The grid follows; it ends the file.
        const std::size_t parent = lengthOf(good, "Tree_float_5_4_3", stock) + 4 + std::strlen("Tree_float_5_4_3");
        REQUIRE(getU32(good, parent) == 0);
        const std::size_t offsets = parent + 4;
        REQUIRE(getI64(good, offsets) == std::int64_t(offsets + 24));
        REQUIRE(getI64(good, offsets + 16) == std::int64_t(good.size()));
        checkRefused(path, with(good, offsets + 8, kHugeOffset),
                     readable + "the offsets of grid 2 at byte " + std::to_string(offsets) + " (grid " +
                         std::to_string(offsets + 24) + ", blocks " + std::to_string(kHugeOffset) + ", end " +
                         std::to_string(good.size()) + ") do not run in order",
                     "the file is damaged");
        checkRefused(path, with(good, offsets + 16, kHugeOffset),
                     "not a complete OpenVDB file (grid 2 ends, by its offsets at byte " + std::to_string(offsets) +
                         ", at byte " + std::to_string(kHugeOffset) + ", past the file's end at byte " +
                         std::to_string(good.size()) + ")",
                     "");
    }
    SECTION("a grid's metadata name and value lengths") {
        // The first grid's "file_compression", a string.
        const std::size_t name = lengthOf(good, "file_compression");
        const std::size_t value = name + 4 + std::strlen("file_compression") + 4 + std::strlen("string");
        REQUIRE(getU32(good, value) == std::strlen("blosc + active values"));
        for (const std::size_t at : {name, value}) {
            INFO("the length at byte " << at);
            checkRefused(path, with(good, at, kHugeLength), readable + "the length " + huge,
                         "of grid 1's metadata, at byte " + std::to_string(at) + ", is more than");
        }
    }
    SECTION("the leaf count in the level set's delayed-load metadata") {
        // Its value: the uint32 length, then the uint32 count of leaves, then a mask of a byte a leaf.
        const std::size_t count = lengthOf(good, "__delayedload", stock) + 4 + std::strlen("__delayedload") + 4;
        REQUIRE(getU32(good, count) == ls.leafCount());
        checkRefused(path, with(good, count, kHugeLength), readable, "of grid 2's metadata");
    }
    SECTION("a grid's metadata name length in a file without offsets") {
        writeWithoutOffsets(dir / "stream.vdb", ls);
        const std::string stream = slurp(dir / "stream.vdb");
        const std::size_t name = lengthOf(stream, "file_compression");
        checkRefused(path, with(stream, name, kHugeLength), readable + "the length " + huge,
                     "of grid 1's metadata, at byte " + std::to_string(name) + ", is more than");
    }
}

TEST_CASE("VDB: the check stops where OpenVDB does, at a metadata entry without a name", "[io][errors]") {
    // OpenVDB refuses an entry with an empty name once it has read it, and reads no further: a
    // damaged length after it is never reached. (So a run of zero bytes under a huge count, which
    // reads as such entries, ends at once rather than being walked to its end.)
    const fs::path dir = testing::scratchFolder("dexelmill_vdb_frame_", "unnamed");
    writeVdb((dir / "part.vdb").string(), dentedBox());
    const std::string good = slurp(dir / "part.vdb");
    // The header: the int64 magic number, the uint32 format version, the library's uint32 major and
    // minor versions, a byte for the grid offsets and the 36 characters of the UUID. The file's
    // metadata count follows; writeVdb writes none.
    constexpr std::size_t kHeaderBytes = 8 + 4 + 4 + 4 + 1 + 36;
    REQUIRE(getU32(good, kHeaderBytes) == 0);
    // Two entries: one with an empty name, type name and value, then one with a huge name length.
    std::string entries(12 + 4, '\0');
    std::memcpy(&entries[12], &kHugeLength, sizeof kHugeLength);
    const fs::path path = dir / "unnamed.vdb";
    spill(path, with(good.substr(0, kHeaderBytes + 4), kHeaderBytes, std::uint32_t(2)) + entries +
                    std::string(64, '\0'));
    CHECK_THROWS_WITH(readVdb(path.string()), Contains("Metadata name cannot be an empty string"));
}
