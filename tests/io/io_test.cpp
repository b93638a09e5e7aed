#include <catch2/catch.hpp>

#include <array>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <random>
#include <sstream>
#include <thread>
#include <vector>

#include <sys/resource.h>

#include <tbb/task_arena.h>

#include "dexelmill/error.h"
#include "dexelmill/io/atomic_file.h"
#include "dexelmill/io/mesh_io.h"
#include "dexelmill/io/picture.h"
#include "dexelmill/io/stock_io.h"
#include "dexelmill/io/vdb_io.h"
#include "dexelmill/surface/levelset.h"
#include "dexelmill/surface/voxelize.h"
#include "support/analytic_parts.h"
#include "support/temp_dir.h"
#include "support/uv_sphere.h"

using namespace dexelmill;
using testing::slurp;
using testing::TempDir;
namespace fs = std::filesystem;

namespace {

const Box kBox{Vec3(0.0), Vec3(24.0, 20.0, 16.0)};
constexpr double kH = 0.5;
/// How many of a VDB's compressed blocks have their size damaged, spread over the file.
constexpr std::size_t kDamagedVdbSizes = 12;

/// Reads of a level set in each of two threads at once: each starts a probe process.
constexpr int kConcurrentReads = 30;

/// A box with a spherical dent in its top: small (48 x 40 x 32 lattice) and closed.
TriDexelStock dentedBox() {
    TriDexelStock stock = TriDexelStock::fromBox(kBox, kH);
    testing::carve(stock, testing::sphere(Vec3(12.0, 10.0, 19.0), 7.0));
    return stock;
}

/// Where a VDB file's Blosc-compressed blocks of voxel values start: each is stored as its size in
/// an int64 (little-endian, as OpenVDB writes on x86) and then the block, whose header begins
/// with Blosc's format versions 2 and 1.
std::vector<std::size_t> bloscBlocks(const std::string& bytes) {
    std::vector<std::size_t> at;
    for (std::size_t k = 0; k + 10 <= bytes.size(); ++k) {
        std::int64_t size = 0;
        std::memcpy(&size, bytes.data() + k, sizeof size);
        if (size > 0 && std::uint64_t(size) <= bytes.size() - k - 8 && bytes[k + 8] == 2 && bytes[k + 9] == 1)
            at.push_back(k);
    }
    return at;
}

/// A cube [lo, hi]^3 as 12 triangles, outward.
Mesh cubeMesh(double lo, double hi) {
    Mesh m;
    for (int i = 0; i < 8; ++i)
        m.vertices.emplace_back(i & 1 ? hi : lo, i & 2 ? hi : lo, i & 4 ? hi : lo);
    const std::uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                       {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) {
        m.triangles.push_back({q[0], q[1], q[2]});
        m.triangles.push_back({q[0], q[2], q[3]});
    }
    return m;
}

}  // namespace

TEST_CASE("mesh files: OBJ, binary STL and PLY", "[io]") {
    TempDir dir;
    const Mesh mesh = meshLevelSet(rebuildLevelSet(dentedBox()));
    REQUIRE(checkMesh(mesh).ok());

    writeStl(dir.file("part.stl"), mesh);
    const std::string stl = slurp(dir.file("part.stl"));
    CHECK(stl.size() == 84 + 50 * mesh.triangles.size());
    const Mesh back = readStl(dir.file("part.stl"));
    CHECK(back.triangles.size() == mesh.triangles.size());
    CHECK(back.vertices.size() == mesh.vertices.size());  // welded again
    const MeshCheck check = checkMesh(back);
    CHECK(check.closedManifold());
    CHECK(check.signedVolume == Approx(meshVolume(mesh)).epsilon(1e-5));

    writePly(dir.file("part.ply"), mesh);
    const std::string ply = slurp(dir.file("part.ply"));
    const std::string header = ply.substr(0, ply.find("end_header\n") + 11);
    CHECK(header.rfind("ply\nformat binary_little_endian 1.0\n", 0) == 0);
    CHECK(header.find("element vertex " + std::to_string(mesh.vertices.size())) != std::string::npos);
    CHECK(ply.size() == header.size() + 12 * mesh.vertices.size() + 13 * mesh.triangles.size());

    // With colours and a scalar per vertex: the first vertex's record holds them after x, y, z.
    PlyVertexData data;
    data.colours.assign(mesh.vertices.size(), Rgb{10, 20, 30});
    data.scalarName = "deviation_mm";
    data.scalar.assign(mesh.vertices.size(), -0.25);
    writePly(dir.file("coloured.ply"), mesh, data);
    const std::string coloured = slurp(dir.file("coloured.ply"));
    const std::size_t body = coloured.find("end_header\n") + 11;
    CHECK(coloured.find("property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float deviation_mm\n") <
          body);
    CHECK(coloured.size() == body + 19 * mesh.vertices.size() + 13 * mesh.triangles.size());
    CHECK(coloured.substr(body + 12, 3) == std::string("\x0a\x14\x1e"));
    float value = 0.0f;
    std::memcpy(&value, coloured.data() + body + 15, 4);
    CHECK(value == -0.25f);
    data.scalar.pop_back();
    CHECK_THROWS_WITH(writePly(dir.file("short.ply"), mesh, data),
                      Catch::Contains("deviation_mm for " + std::to_string(mesh.vertices.size() - 1)));
    data.scalar.push_back(0.0);
    data.scalarName = "two words";
    CHECK_THROWS_AS(writePly(dir.file("short.ply"), mesh, data), Error);
    fs::remove(dir.file("coloured.ply"));

    writeObj(dir.file("part.obj"), mesh);
    std::istringstream obj(slurp(dir.file("part.obj")));
    std::size_t v = 0, f = 0;
    Vec3 first(0.0);
    for (std::string line; std::getline(obj, line);) {
        if (line.rfind("v ", 0) == 0) {
            if (v == 0) std::istringstream(line.substr(2)) >> first.x >> first.y >> first.z;
            ++v;
        }
        if (line.rfind("f ", 0) == 0) ++f;
    }
    CHECK(v == mesh.vertices.size());
    CHECK(f == mesh.triangles.size());
    CHECK(first == mesh.vertices[0]);  // shortest round-trip decimals
    CHECK(dir.entries() == 3);
}

TEST_CASE("binary STL: a mesh many buffers long is written record by record, in order, on any thread count",
          "[io]") {
    // 100,003 triangles span several of the writer's buffers, the last one partly; every tenth
    // repeats a corner, so its normal must be zero.
    std::mt19937 rng(20261124);
    std::uniform_real_distribution<double> coord(-500.0, 500.0);
    Mesh mesh;
    for (int i = 0; i < 20011; ++i) mesh.vertices.push_back({coord(rng), coord(rng), coord(rng)});
    std::uniform_int_distribution<std::uint32_t> pick(0, std::uint32_t(mesh.vertices.size() - 1));
    for (int t = 0; t < 100003; ++t) {
        const std::uint32_t a = pick(rng), b = pick(rng);
        mesh.triangles.push_back({a, b, t % 10 == 0 ? a : pick(rng)});
    }
    auto f32 = [](const std::string& bytes, std::size_t at) {
        std::uint32_t bits = 0;
        for (int i = 0; i < 4; ++i) bits |= std::uint32_t(static_cast<unsigned char>(bytes[at + std::size_t(i)])) << (8 * i);
        float f = 0.0f;
        std::memcpy(&f, &bits, 4);
        return f;
    };
    TempDir dir;
    for (const int threads : {1, 2, 3}) {
        tbb::task_arena(threads).execute([&] { writeStl(dir.file("many.stl"), mesh); });
        const std::string stl = slurp(dir.file("many.stl"));
        REQUIRE(stl.size() == 84 + 50 * mesh.triangles.size());
        CHECK(stl.substr(0, 24) == "dexelmill binary STL, mm");
        std::uint32_t count = 0;
        for (int i = 0; i < 4; ++i) count |= std::uint32_t(static_cast<unsigned char>(stl[80 + std::size_t(i)])) << (8 * i);
        CHECK(count == mesh.triangles.size());
        std::size_t wrong = 0;
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
            const std::size_t at = 84 + 50 * t;
            const Vec3 a = mesh.vertices[mesh.triangles[t][0]], b = mesh.vertices[mesh.triangles[t][1]],
                       c = mesh.vertices[mesh.triangles[t][2]];
            const Vec3 cross = glm::cross(b - a, c - a);
            const double length = glm::length(cross);
            for (int k = 0; k < 3; ++k) {
                const float expected = length > 0.0 ? float(cross[k] / length) : 0.0f;
                wrong += f32(stl, at + 4 * std::size_t(k)) != expected;
                for (int corner = 0; corner < 3; ++corner)
                    wrong += f32(stl, at + 12 + 12 * std::size_t(corner) + 4 * std::size_t(k)) !=
                             float(mesh.vertices[mesh.triangles[t][std::size_t(corner)]][k]);
            }
            wrong += stl[at + 48] != 0 || stl[at + 49] != 0;
        }
        CHECK(wrong == 0);
    }
}

TEST_CASE("STL: ASCII is parsed, a binary file starting with 'solid' is binary", "[io]") {
    TempDir dir;
    const Mesh cube = cubeMesh(0.0, 2.0);
    std::ostringstream ascii;
    ascii << "solid cube\n";
    for (std::size_t t = 0; t < cube.triangles.size(); ++t) {
        ascii << "  facet normal 0 0 0\n    outer loop\n";
        for (std::uint32_t i : cube.triangles[t])
            ascii << "      vertex " << cube.vertices[i].x << " " << cube.vertices[i].y << " "
                  << cube.vertices[i].z << "\n";
        ascii << "    endloop\n  endfacet\n";
    }
    ascii << "endsolid cube\n";
    writeStreamAtomically(dir.file("a.stl"), [&](std::ostream& o) { o << ascii.str(); });
    const Mesh a = readStl(dir.file("a.stl"));
    CHECK(a.vertices.size() == 8);
    CHECK(checkMesh(a).ok());
    CHECK(meshVolume(a) == Approx(8.0));

    // A binary STL whose 80-byte header begins with "solid".
    writeStl(dir.file("b.stl"), cube);
    std::string bin = slurp(dir.file("b.stl"));
    bin.replace(0, 6, "solid ");
    writeStreamAtomically(dir.file("b.stl"), [&](std::ostream& o) { o << bin; });
    CHECK(meshVolume(readStl(dir.file("b.stl"))) == Approx(8.0));

    std::string bad = ascii.str();
    bad.replace(bad.find("vertex 0 0 0"), 12, "vertex 0 x 0");
    writeStreamAtomically(dir.file("bad.stl"), [&](std::ostream& o) { o << bad; });
    try {
        readStl(dir.file("bad.stl"));
        FAIL("no ParseError");
    } catch (const ParseError& e) {
        CHECK(e.where().line == 4);
        CHECK(e.offending() == "x");
    }
    CHECK_THROWS_AS(readStl(dir.file("missing.stl")), Error);
    // A binary STL with a corner that is not a number.
    std::string nan = slurp(dir.file("b.stl"));
    const float notANumber = std::nanf("");
    std::memcpy(&nan[84 + 50 + 12 + 4], &notANumber, 4);  // the second triangle's first corner's y
    writeStreamAtomically(dir.file("nan.stl"), [&](std::ostream& o) { o << nan; });
    CHECK_THROWS_WITH(readStl(dir.file("nan.stl")), Catch::Contains("triangle 2") && Catch::Contains("finite"));
    fs::create_directories(dir.file("folder.stl"));
    CHECK_THROWS_WITH(readStl(dir.file("folder.stl")), Catch::Contains("folder"));
    // A binary STL cut short, or with bytes after its last record, whether or not its header
    // begins with "solid": the count's size and the file's are named.
    const std::string whole = slurp(dir.file("b.stl"));
    REQUIRE(whole.size() == 84 + 50 * 12);
    for (const std::size_t size : {std::size_t(84 + 50 * 12 - 7), std::size_t(100), std::size_t(84)}) {
        writeStreamAtomically(dir.file("cut.stl"), [&](std::ostream& o) { o << whole.substr(0, size); });
        CHECK_THROWS_WITH(readStl(dir.file("cut.stl")),
                          Catch::Contains("counts 12 triangles") && Catch::Contains("684 bytes") &&
                              Catch::Contains("has " + std::to_string(size)));
    }
    writeStreamAtomically(dir.file("long.stl"), [&](std::ostream& o) { o << whole << "extra"; });
    CHECK_THROWS_WITH(readStl(dir.file("long.stl")), Catch::Contains("has 689"));
    // An ASCII STL whose name runs past byte 80 with control bytes in it is still text.
    std::string padded = ascii.str();
    padded.replace(0, std::string("solid cube").size(), "solid " + std::string(90, 'n') + std::string(4, '\0'));
    writeStreamAtomically(dir.file("padded.stl"), [&](std::ostream& o) { o << padded; });
    CHECK(meshVolume(readStl(dir.file("padded.stl"))) == Approx(8.0));
}

TEST_CASE("STL: equal corners are welded in order of appearance, -0 with +0", "[io]") {
    TempDir dir;
    Mesh m;
    m.vertices = {Vec3(0.0), Vec3(1.0, 0.0, 0.0), Vec3(0.0, 1.0, 0.0), Vec3(-0.0, -0.0, -0.0), Vec3(2.0, 2.0, 2.0)};
    // The second triangle names the origin as -0; the third collapses onto an edge once welded.
    m.triangles = {{4, 1, 2}, {3, 2, 1}, {0, 3, 1}};
    writeStl(dir.file("w.stl"), m);
    const Mesh w = readStl(dir.file("w.stl"));
    REQUIRE(w.vertices.size() == 4);
    CHECK(w.vertices[0] == Vec3(2.0, 2.0, 2.0));
    CHECK(w.vertices[1] == Vec3(1.0, 0.0, 0.0));
    CHECK(w.vertices[2] == Vec3(0.0, 1.0, 0.0));
    CHECK(w.vertices[3] == Vec3(0.0));
    REQUIRE(w.triangles.size() == 2);
    CHECK(w.triangles[0] == Mesh::Triangle{0, 1, 2});
    CHECK(w.triangles[1] == Mesh::Triangle{3, 2, 1});
}

TEST_CASE("STL: welding many corners agrees with a brute-force weld", "[io]") {
    // 3,000 triangles whose corners come from a pool of 4,000 points (some given as -0), so the
    // vertices outnumber a closed mesh's and the weld's table must grow; some triangles collapse.
    // The file is written byte by byte here, and the oracle welds with an ordered map.
    std::mt19937 rng(20261124);
    std::uniform_int_distribution<int> pick(0, 3999), coord(-3, 3);
    std::vector<std::array<float, 3>> pool(4000);
    for (auto& p : pool)
        for (float& c : p) c = float(coord(rng)) * 0.5f + float(pick(rng)) * 1e-3f;
    for (std::size_t i = 0; i < pool.size(); i += 97) pool[i][1] = 0.0f;
    const std::size_t triangles = 3000;
    std::vector<std::array<float, 3>> corners;
    for (std::size_t t = 0; t < triangles; ++t)
        for (int k = 0; k < 3; ++k) {
            std::array<float, 3> c = pool[std::size_t(pick(rng))];
            if (c[1] == 0.0f && k == 1) c[1] = -0.0f;
            corners.push_back(c);
        }
    corners[3 * 7 + 2] = corners[3 * 7];  // a triangle with two equal corners
    TempDir dir;
    {
        std::ofstream out(dir.file("soup.stl"), std::ios::binary);
        const std::string head(80, ' ');
        out.write(head.data(), 80);
        const auto count = std::uint32_t(triangles);
        out.write(reinterpret_cast<const char*>(&count), 4);  // the test machine is little-endian
        for (std::size_t t = 0; t < triangles; ++t) {
            const float normal[3] = {0.0f, 0.0f, 0.0f};
            out.write(reinterpret_cast<const char*>(normal), 12);
            for (int k = 0; k < 3; ++k) out.write(reinterpret_cast<const char*>(corners[3 * t + std::size_t(k)].data()), 12);
            out.write("\0\0", 2);
        }
    }
    // The oracle: numbered in order of first appearance, -0 as +0, collapsed triangles dropped.
    auto key = [](const std::array<float, 3>& c) {
        std::array<std::uint32_t, 3> k{};
        for (int i = 0; i < 3; ++i) {
            const float v = c[std::size_t(i)] == 0.0f ? 0.0f : c[std::size_t(i)];
            std::memcpy(&k[std::size_t(i)], &v, 4);
        }
        return k;
    };
    std::map<std::array<std::uint32_t, 3>, std::uint32_t> number;
    std::vector<std::array<float, 3>> vertices;
    std::vector<Mesh::Triangle> expected;
    for (std::size_t t = 0; t < triangles; ++t) {
        Mesh::Triangle tri{};
        for (int k = 0; k < 3; ++k) {
            const auto& c = corners[3 * t + std::size_t(k)];
            const auto [it, fresh] = number.emplace(key(c), std::uint32_t(vertices.size()));
            if (fresh) vertices.push_back(c);
            tri[std::size_t(k)] = it->second;
        }
        if (tri[0] != tri[1] && tri[1] != tri[2] && tri[2] != tri[0]) expected.push_back(tri);
    }
    REQUIRE(vertices.size() > 3000);  // more than half of a table sized for a closed mesh
    REQUIRE(expected.size() < triangles);
    const Mesh w = readStl(dir.file("soup.stl"));
    REQUIRE(w.vertices.size() == vertices.size());
    for (std::size_t v = 0; v < vertices.size(); ++v) {
        INFO("vertex " << v);
        CHECK(w.vertices[v] == Vec3(vertices[v][0], vertices[v][1], vertices[v][2]));
        CHECK(std::signbit(w.vertices[v].y) == std::signbit(vertices[v][1]));
    }
    CHECK(w.triangles == std::vector<Mesh::Triangle, NoZeroAllocator<Mesh::Triangle>>(expected.begin(), expected.end()));
}

TEST_CASE("VDB: a level set written and read back is identical", "[io]") {
    TempDir dir;
    const LevelSet ls = rebuildLevelSet(dentedBox(), {3, FamilySet::all(), "dented box", std::nullopt});
    writeVdb(dir.file("part.vdb"), ls);
    const LevelSet back = readVdb(dir.file("part.vdb"));
    CHECK(back.source() == "dented box");
    CHECK(back.voxelSize() == ls.voxelSize());
    CHECK(back.halfWidth() == ls.halfWidth());
    CHECK(back.activeVoxelCount() == ls.activeVoxelCount());
    CHECK(back.leafCount() == ls.leafCount());
    REQUIRE(back.lattice().has_value());
    CHECK(back.lattice()->n == ls.lattice()->n);
    CHECK(back.lattice()->origin == ls.lattice()->origin);
    // Every voxel of the padded lattice, active or not, holds the same value.
    const auto n = ls.lattice()->n;
    std::size_t differ = 0;
    for (int k = -6; k < n[2] + 6; ++k)
        for (int j = -6; j < n[1] + 6; ++j)
            for (int i = -6; i < n[0] + 6; ++i)
                differ += ls.voxelValue(i, j, k) != back.voxelValue(i, j, k);
    CHECK(differ == 0);
    CHECK(back.valueAt(Vec3(3.3, 4.4, 5.5)) == ls.valueAt(Vec3(3.3, 4.4, 5.5)));
    CHECK_THROWS_AS(readVdb(dir.file("part.vdb"), "nope"), Error);
    CHECK_THROWS_AS(readVdb(dir.file("missing.vdb")), Error);
}

TEST_CASE("VDB: a file cut short anywhere is refused as incomplete, naming it", "[io][errors]") {
    TempDir dir;
    const LevelSet ls = rebuildLevelSet(dentedBox(), {3, FamilySet::all(), "dented box", std::nullopt});
    writeVdb(dir.file("part.vdb"), ls);
    std::ifstream in(dir.file("part.vdb"), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    REQUIRE(bytes.size() > 4000);
    // Cuts in the header, the metadata, the topology and the voxel buffers, and one byte short.
    std::vector<std::size_t> cuts = {1, 8, 100, 3000, bytes.size() - 1};
    for (std::size_t k = 1; k < 16; ++k) cuts.push_back(bytes.size() * k / 16);
    for (const std::size_t cut : cuts) {
        INFO("the first " << cut << " of " << bytes.size() << " bytes");
        const std::string path = dir.file("cut.vdb");
        std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(cut));
        // Refused by OpenVDB's stream where the file ends, or before it by the grid's end offset.
        CHECK_THROWS_WITH(readVdb(path), Catch::Matchers::StartsWith("'" + path + "': not a complete OpenVDB file ("));
    }
    CHECK_THROWS_WITH(readVdb(dir.path.string()), Catch::Matchers::Contains("is not a regular file"));
}

TEST_CASE("VDB: level sets are read in two threads at once", "[io][errors]") {
    // readVdb reads a file first in a process of its own. As a fork of this one, that process held
    // every lock another thread held at the fork, and waited for ever on the first it needed:
    // OpenVDB's registry of grid types, which the other thread's read takes, say. (1 run in some
    // 40 of the test above hung so, where TBB's workers, which OpenVDB uses to free a tree, were
    // still busy.) A new program inherits no lock.
    TempDir dir;
    const LevelSet ls = rebuildLevelSet(dentedBox(), {3, FamilySet::all(), "dented box", std::nullopt});
    writeVdb(dir.file("part.vdb"), ls);
    const std::string bytes = slurp(dir.file("part.vdb"));
    const std::string cut = dir.file("cut.vdb");
    std::ofstream(cut, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size() * 3 / 4));
    std::atomic<int> read{0}, refused{0};
    const auto reads = [&](const std::string& path) {
        for (int k = 0; k < kConcurrentReads; ++k) {
            try {
                if (readVdb(path).activeVoxelCount() > 0) ++read;
            } catch (const Error&) {
                ++refused;
            }
        }
    };
    std::thread other(reads, dir.file("part.vdb"));
    reads(cut);
    other.join();
    CHECK(read == kConcurrentReads);
    CHECK(refused == kConcurrentReads);
}

TEST_CASE("VDB: a damaged size of compressed data is refused and never crashes", "[io][errors]") {
    // Each block of voxel values OpenVDB compresses (Blosc, the default) is stored as its size
    // and then the block (bloscBlocks). A negative size marks a block stored raw, of minus that many bytes, and OpenVDB 10 reads it
    // into a buffer of the node's size whatever it says: made -65536, each size wrote past the
    // buffer and aborted the process ("double free or corruption", "free(): invalid pointer").
    TempDir dir;
    const LevelSet ls = rebuildLevelSet(dentedBox(), {3, FamilySet::all(), "dented box", std::nullopt});
    writeVdb(dir.file("part.vdb"), ls);
    const std::string bytes = slurp(dir.file("part.vdb"));
    const std::vector<std::size_t> sizes = bloscBlocks(bytes);
    REQUIRE(sizes.size() >= kDamagedVdbSizes);
    for (std::size_t k = 0; k < kDamagedVdbSizes; ++k) {
        const std::size_t at = sizes[k * sizes.size() / kDamagedVdbSizes];
        INFO("the size at byte " << at << " of " << bytes.size() << " made -65536");
        std::string damaged = bytes;
        const std::int64_t raw = -65536;
        std::memcpy(&damaged[at], &raw, sizeof raw);
        const std::string path = dir.file("damaged.vdb");
        std::ofstream(path, std::ios::binary | std::ios::trunc).write(damaged.data(), std::streamsize(damaged.size()));
        CHECK_THROWS_WITH(readVdb(path), Catch::Matchers::StartsWith("'" + path + "': not a readable OpenVDB file"));
    }
}

TEST_CASE("VDB: a compressed block Blosc cannot expand is refused in a user's words", "[io][errors]") {
    // A block's Blosc header starts with its format version, 2; made 3, Blosc refuses the block
    // and OpenVDB throws "RuntimeError: Expected to decompress 1568 bytes, got -1 bytes".
    TempDir dir;
    const LevelSet ls = rebuildLevelSet(dentedBox(), {3, FamilySet::all(), "dented box", std::nullopt});
    writeVdb(dir.file("part.vdb"), ls);
    std::string bytes = slurp(dir.file("part.vdb"));
    const std::vector<std::size_t> blocks = bloscBlocks(bytes);
    REQUIRE(blocks.size() >= 2);
    const std::size_t block = blocks[blocks.size() / 2];
    INFO("the Blosc block whose size is at byte " << block << " of " << bytes.size());
    bytes[block + 8] = 3;
    const std::string path = dir.file("damaged.vdb");
    std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
    CHECK_THROWS_WITH(readVdb(path), Catch::Matchers::StartsWith("'" + path + "': not a readable OpenVDB file (OpenVDB: ") &&
                                         Catch::Matchers::Contains("decompress") &&
                                         !Catch::Matchers::Contains("RuntimeError") &&
                                         Catch::Matchers::EndsWith("the file is damaged, or holds what this OpenVDB cannot read)"));
}

namespace {

/// While alive, writes past `bytes` in any file fail (EFBIG) as on a full disk: a file-size limit,
/// with SIGXFSZ, which would end the process, ignored.
class FileSizeLimit {
public:
    explicit FileSizeLimit(::rlim_t bytes) {
        ::getrlimit(RLIMIT_FSIZE, &old_);
        signal_ = std::signal(SIGXFSZ, SIG_IGN);
        ::rlimit limit = old_;
        limit.rlim_cur = bytes;
        ::setrlimit(RLIMIT_FSIZE, &limit);
    }
    ~FileSizeLimit() {
        ::setrlimit(RLIMIT_FSIZE, &old_);
        std::signal(SIGXFSZ, signal_);
    }

private:
    ::rlimit old_{};
    void (*signal_)(int) = nullptr;
};

}  // namespace

TEST_CASE("every writer fails on a full disk and leaves the file it would replace", "[io]") {
    TempDir dir;
    const TriDexelStock stock = dentedBox();
    const LevelSet ls = rebuildLevelSet(stock);
    const Mesh mesh = meshLevelSet(ls);
    const std::map<std::string, std::function<void(const std::string&)>> writers{
        {"part.vdb", [&](const std::string& p) { writeVdb(p, ls); }},
        {"part.stl", [&](const std::string& p) { writeStl(p, mesh); }},
        {"part.obj", [&](const std::string& p) { writeObj(p, mesh); }},
        {"part.ply", [&](const std::string& p) { writePly(p, mesh); }},
        {"part.png", [&](const std::string& p) { writePicture(p, mesh); }}};
    for (const auto& [name, write] : writers) {
        INFO(name);
        std::ofstream(dir.file(name)) << "KEEP";
        {
            // Each file is larger than 4 KiB.
            const FileSizeLimit full(4096);
            CHECK_THROWS_AS(write(dir.file(name)), Error);
        }
        CHECK(slurp(dir.file(name)) == "KEEP");
    }
    CHECK(dir.entries() == writers.size());
}

TEST_CASE("stock from a mesh: lines through edges and vertices cross once", "[io][surface]") {
    // Lattice points at integer coordinates: every x, y and z line through the cube's faces at
    // integer positions passes through triangle edges, and the diagonals hit vertices.
    Lattice lat;
    lat.origin = Vec3(-2.5);
    lat.h = 1.0;
    lat.n = {15, 15, 15};
    lat.stockMax = lat.cellBox().hi;
    MeshCastStats stats;
    const TriDexelStock stock = stockFromMesh(cubeMesh(0.0, 10.0), lat, FamilySet::all(), &stats);
    CHECK(stats.unpairedDexels == 0);
    for (int a = 0; a < 3; ++a) {
        const DexelFamily& fam = stock.family(axisFromIndex(a));
        for (int ic = 0; ic < fam.nc(); ++ic) {
            for (int ib = 0; ib < fam.nb(); ++ib) {
                const SegmentSpan segs = fam.segments(ib, ic);
                // Strictly inside the square (lattice coordinates 1..9): exactly [2.5, 12.5].
                const double yb = lat.coord(fam.axisB(), ib), yc = lat.coord(fam.axisC(), ic);
                if (yb > 0.0 && yb < 10.0 && yc > 0.0 && yc < 10.0) {
                    REQUIRE(segs.size == 1);
                    CHECK(segs[0].lo == 2.5f);
                    CHECK(segs[0].hi == 12.5f);
                    // The ends take the cube faces' normals, which pack exactly.
                    CHECK(segs[0].nlo.unpack() == -axisVector(axisFromIndex(a)));
                    CHECK(segs[0].nhi.unpack() == axisVector(axisFromIndex(a)));
                } else if (yb < 0.0 || yb > 10.0 || yc < 0.0 || yc > 10.0) {
                    CHECK(segs.empty());
                } else {
                    CHECK(segs.size <= 1);  // on the boundary: the top-left rule decides
                }
            }
        }
    }
}

TEST_CASE("stock from a mesh: a faceted sphere", "[io][surface]") {
    Mesh sphere = testing::uvSphere(24, 48, 8.0);
    for (Vec3& v : sphere.vertices) v += Vec3(10.0);
    REQUIRE(checkMesh(sphere).ok());
    const Lattice lat = Lattice::fromBox(sphere.bounds().padded(1.0), 0.25);
    MeshCastStats stats;
    const TriDexelStock stock = stockFromMesh(sphere, lat, FamilySet::all(), &stats);
    CHECK(stats.unpairedDexels == 0);
    const double v = meshVolume(sphere);
    for (int a = 0; a < 3; ++a) CHECK(stock.volume(axisFromIndex(a)) == Approx(v).epsilon(0.005));
    // Every end's normal is the facet's it crosses: within half a facet's angle (7.5 and 3.75
    // degrees across the bands and around) of the sphere's radial direction there.
    double worst = 1.0;
    for (int a = 0; a < 3; ++a) {
        const Axis axis = axisFromIndex(a);
        const DexelFamily& fam = stock.family(axis);
        for (int ic = 0; ic < fam.nc(); ++ic)
            for (int ib = 0; ib < fam.nb(); ++ib) {
                const Line line = stock.dexelLine(axis, ib, ic);
                for (const Segment& g : fam.segments(ib, ic)) {
                    REQUIRE(g.nlo.present());
                    REQUIRE(g.nhi.present());
                    worst = std::min(worst, glm::dot(g.nlo.unpack(), glm::normalize(line.at(g.lo) - Vec3(10.0))));
                    worst = std::min(worst, glm::dot(g.nhi.unpack(), glm::normalize(line.at(g.hi) - Vec3(10.0))));
                }
            }
    }
    INFO("least cosine between an end's normal and the radial direction: " << worst);
    CHECK(worst > std::cos(9.0 * 3.14159265358979 / 180.0));
    // And back: the rebuilt surface is closed with the same volume.
    const MeshCheck check = checkMesh(meshLevelSet(rebuildLevelSet(stock)));
    CHECK(check.ok());
    CHECK(check.signedVolume == Approx(v).epsilon(0.005));
}

TEST_CASE("stock from files: STL and VDB", "[io]") {
    TempDir dir;
    const TriDexelStock original = dentedBox();
    const LevelSet ls = rebuildLevelSet(original, {3, FamilySet::all(), "dented", std::nullopt});
    writeVdb(dir.file("part.vdb"), ls);
    writeStl(dir.file("part.stl"), meshLevelSet(ls));
    const double v = original.volume(Axis::Z);

    // VDB with the recorded lattice: the same dexels, endpoints within a small fraction of h.
    const TriDexelStock fromVdb = readStock(dir.file("part.vdb"), kH);
    REQUIRE(fromVdb.lattice().n == original.lattice().n);
    // The level set rounds sharp edges a little (the distance estimate is not planar there): the
    // worst endpoints lie on the box's edges and the dent's rim. The RMS leaves out dexels within
    // 2 h of a box face across them.
    double worstAll = 0.0, sum2 = 0.0, angle2 = 0.0;
    std::size_t countMismatch = 0, ends = 0;
    auto nearFace = [&](Axis axis, double coord) {
        const int i = index(axis);
        return coord - kBox.lo[i] < 2 * kH || kBox.hi[i] - coord < 2 * kH;
    };
    for (int a = 0; a < 3; ++a) {
        const DexelFamily& f0 = original.family(axisFromIndex(a));
        const DexelFamily& f1 = fromVdb.family(axisFromIndex(a));
        const Lattice& lat = original.lattice();
        for (int ic = 0; ic < f0.nc(); ++ic)
            for (int ib = 0; ib < f0.nb(); ++ib) {
                const SegmentSpan s0 = f0.segments(ib, ic), s1 = f1.segments(ib, ic);
                if (s0.size != s1.size) {
                    ++countMismatch;
                    continue;
                }
                const bool edge = nearFace(f0.axisB(), lat.coord(f0.axisB(), ib)) ||
                                  nearFace(f0.axisC(), lat.coord(f0.axisC(), ic));
                for (std::size_t s = 0; s < s0.size; ++s) {
                    const double dlo = s0[s].lo - s1[s].lo, dhi = s0[s].hi - s1[s].hi;
                    worstAll = std::max({worstAll, std::abs(dlo), std::abs(dhi)});
                    REQUIRE(s1[s].nlo.present());
                    REQUIRE(s1[s].nhi.present());
                    if (edge) continue;
                    sum2 += dlo * dlo + dhi * dhi;
                    ends += 2;
                    // The field's gradient against the carved solid's exact normals.
                    for (const auto& [n0, n1] : {std::pair{s0[s].nlo, s1[s].nlo}, std::pair{s0[s].nhi, s1[s].nhi}}) {
                        const double angle = std::acos(std::clamp(glm::dot(n0.unpack(), n1.unpack()), -1.0, 1.0));
                        angle2 += angle * angle;
                    }
                }
            }
    }
    CHECK(countMismatch == 0);
    CHECK(worstAll <= 0.25 * kH);
    CHECK(std::sqrt(sum2 / double(ends)) <= 0.02 * kH);
    // Normals from the interpolated field's gradient: within a few degrees (RMS) of the exact ones
    // (measured 0.052 rad; the field itself is a distance estimate that bends near edges).
    INFO("RMS angle of the VDB stock's normals: " << std::sqrt(angle2 / double(ends)) << " rad");
    CHECK(std::sqrt(angle2 / double(ends)) < 0.08);
    CHECK(fromVdb.volume(Axis::Z) == Approx(v).epsilon(0.005));

    // VDB at another spacing: a fresh lattice on the material box.
    const TriDexelStock coarse = readStock(dir.file("part.vdb"), 2 * kH, FamilySet::only(Axis::Z));
    CHECK(coarse.volume(Axis::Z) == Approx(v).epsilon(0.02));

    MeshCastStats stats;
    const TriDexelStock fromStl = readStock(dir.file("part.stl"), kH, FamilySet::all(), &stats);
    CHECK(stats.unpairedDexels == 0);
    for (int a = 0; a < 3; ++a)
        CHECK(fromStl.volume(axisFromIndex(a)) == Approx(v).epsilon(0.005));
    CHECK_THROWS_AS(readStock(dir.file("part.txt"), kH), Error);
    CHECK_THROWS_AS(readStock(dir.file("part.stl"), 0.0), Error);
}

TEST_CASE("picture: an isometric PNG of the part", "[io]") {
    TempDir dir;
    const Mesh mesh = meshLevelSet(rebuildLevelSet(dentedBox()));
    PictureOptions opt;
    opt.width = 160;
    opt.height = 120;
    const Image img = renderPicture(mesh, opt);
    REQUIRE(img.rgb.size() == 160u * 120u * 3u);
    // The part fills the middle; the corners are background.
    const std::uint8_t* corner = img.pixel(0, 0);
    const std::uint8_t* middle = img.pixel(80, 60);
    CHECK((corner[0] != middle[0] || corner[1] != middle[1] || corner[2] != middle[2]));
    writePng(dir.file("part.png"), img);
    const std::string png = slurp(dir.file("part.png"));
    REQUIRE(png.size() > 8);
    CHECK(png.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0);
    CHECK_THROWS_AS(renderPicture(mesh, PictureOptions{0, 10, 1, Vec3(1.0), 0.05}), Error);
}
