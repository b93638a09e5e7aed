#include "dexelmill/io/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string_view>
#include <vector>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "dexelmill/error.h"
#include "dexelmill/io/atomic_file.h"
#include "io/detail/binary.h"
#include "memory/pages.h"

namespace dexelmill {

namespace {

/// Buffers output and hands it to the stream in large blocks.
class BlockWriter {
public:
    explicit BlockWriter(std::ostream& out) : out_(out) { buf_.reserve(kBlock + 256); }
    ~BlockWriter() = default;

    void put(const char* s, std::size_t n) {
        buf_.append(s, n);
        if (buf_.size() >= kBlock) flush();
    }
    void put(const std::string& s) { put(s.data(), s.size()); }
    void put(char c) {
        buf_.push_back(c);
        if (buf_.size() >= kBlock) flush();
    }
    void number(double v) {
        char tmp[32];
        const auto res = std::to_chars(tmp, tmp + sizeof(tmp), v);
        put(tmp, std::size_t(res.ptr - tmp));
    }
    void number(std::uint64_t v) {
        char tmp[24];
        const auto res = std::to_chars(tmp, tmp + sizeof(tmp), v);
        put(tmp, std::size_t(res.ptr - tmp));
    }
    void flush() {
        out_.write(buf_.data(), std::streamsize(buf_.size()));
        buf_.clear();
    }

private:
    static constexpr std::size_t kBlock = 1 << 20;
    std::ostream& out_;
    std::string buf_;
};

/// A binary STL record: normal, three corners (twelve floats) and a two-byte attribute count.
constexpr std::size_t kStlRecord = 50;
/// Triangles formatted into one buffer by one task (1.6 MB).
constexpr std::size_t kStlChunk = std::size_t(1) << 15;

void requireValidIndices(const Mesh& mesh) {
    for (const Mesh::Triangle& t : mesh.triangles)
        for (std::uint32_t i : t)
            if (i >= mesh.vertices.size()) throw Error("mesh has a vertex index past its vertex list");
}

}  // namespace

void writeObj(const std::string& path, const Mesh& mesh, OutputBatch* batch) {
    requireValidIndices(mesh);
    writeStreamAtomically(path, [&](std::ostream& out) {
        BlockWriter w(out);
        w.put("# dexelmill mesh: " + std::to_string(mesh.vertices.size()) + " vertices, " +
              std::to_string(mesh.triangles.size()) + " triangles, mm\n");
        for (const Vec3& v : mesh.vertices) {
            w.put("v ", 2);
            w.number(v.x);
            w.put(' ');
            w.number(v.y);
            w.put(' ');
            w.number(v.z);
            w.put('\n');
        }
        for (const Mesh::Triangle& t : mesh.triangles) {
            w.put("f ", 2);
            w.number(std::uint64_t(t[0]) + 1);
            w.put(' ');
            w.number(std::uint64_t(t[1]) + 1);
            w.put(' ');
            w.number(std::uint64_t(t[2]) + 1);
            w.put('\n');
        }
        w.flush();
    }, batch);
}

void writeStl(const std::string& path, const Mesh& mesh, OutputBatch* batch) {
    requireValidIndices(mesh);
    if (mesh.triangles.size() > std::numeric_limits<std::uint32_t>::max())
        throw Error("binary STL holds at most 2^32 - 1 triangles");
    writeStreamAtomically(path, [&](std::ostream& out) {
        char header[80] = {};
        std::snprintf(header, sizeof(header), "dexelmill binary STL, mm");
        out.write(header, sizeof(header));
        char count[4];
        binary::putU32(count, std::uint32_t(mesh.triangles.size()));
        out.write(count, sizeof(count));
        // Records are formatted in parallel, a chunk of triangles per buffer, a few chunks per
        // thread at a time, and written in order, so the file does not depend on the thread
        // count. The formatting is the small part: on the hood (29 million triangles) perf gives
        // 14 % of the stage to it and 41 % to the kernel's copy into the page cache, and the
        // fsync takes about 1 s.
        const std::size_t n = mesh.triangles.size();
        const std::size_t chunks = (n + kStlChunk - 1) / kStlChunk;
        const std::size_t batch = 2 * std::size_t(std::max(1, tbb::this_task_arena::max_concurrency()));
        std::vector<std::vector<char>> buffers(std::min(batch, chunks));
        for (std::size_t c0 = 0; c0 < chunks; c0 += batch) {
            const std::size_t c1 = std::min(chunks, c0 + batch);
            tbb::parallel_for(c0, c1, [&](std::size_t c) {
                const std::size_t t0 = c * kStlChunk, t1 = std::min(n, t0 + kStlChunk);
                std::vector<char>& buffer = buffers[c - c0];
                buffer.resize(kStlRecord * (t1 - t0));
                char* p = buffer.data();
                for (std::size_t t = t0; t < t1; ++t) {
                    const Vec3 a = mesh.areaVector(t);
                    const double len = glm::length(a);
                    const Vec3 normal = len > 0.0 ? a / len : Vec3(0.0);
                    for (int k = 0; k < 3; ++k) p = binary::putF32(p, float(normal[k]));
                    for (std::uint32_t vi : mesh.triangles[t])
                        for (int k = 0; k < 3; ++k) p = binary::putF32(p, float(mesh.vertices[vi][k]));
                    p[0] = p[1] = 0;
                    p += 2;
                }
            });
            for (std::size_t c = c0; c < c1; ++c)
                out.write(buffers[c - c0].data(), std::streamsize(buffers[c - c0].size()));
        }
    }, batch);
}

void writePly(const std::string& path, const Mesh& mesh, const PlyVertexData& data, OutputBatch* batch) {
    requireValidIndices(mesh);
    const std::size_t n = mesh.vertices.size();
    const bool colours = !data.colours.empty(), scalar = !data.scalar.empty();
    if (colours && data.colours.size() != n)
        throw Error("cannot write '" + path + "': colours for " + std::to_string(data.colours.size()) + " of " +
                    std::to_string(n) + " vertices");
    if (scalar && data.scalar.size() != n)
        throw Error("cannot write '" + path + "': " + data.scalarName + " for " + std::to_string(data.scalar.size()) +
                    " of " + std::to_string(n) + " vertices");
    if (scalar && (data.scalarName.empty() || data.scalarName.find_first_of(" \t\n") != std::string::npos))
        throw Error("cannot write '" + path + "': a PLY property needs a name without spaces");
    writeStreamAtomically(path, [&](std::ostream& out) {
        BlockWriter w(out);
        std::string header = "ply\nformat binary_little_endian 1.0\ncomment dexelmill mesh, mm\nelement vertex " +
                             std::to_string(n) + "\nproperty float x\nproperty float y\nproperty float z\n";
        if (colours) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
        if (scalar) header += "property float " + data.scalarName + "\n";
        header += "element face " + std::to_string(mesh.triangles.size()) +
                  "\nproperty list uchar int vertex_indices\nend_header\n";
        w.put(header);
        char rec[19];
        for (std::size_t i = 0; i < n; ++i) {
            char* p = rec;
            for (int k = 0; k < 3; ++k) p = binary::putF32(p, float(mesh.vertices[i][k]));
            if (colours)
                for (std::uint8_t c : data.colours[i]) *p++ = char(c);
            if (scalar) p = binary::putF32(p, float(data.scalar[i]));
            w.put(rec, std::size_t(p - rec));
        }
        for (const Mesh::Triangle& t : mesh.triangles) {
            rec[0] = 3;
            char* p = rec + 1;
            for (std::uint32_t vi : t) p = binary::putU32(p, vi);
            w.put(rec, 13);
        }
        w.flush();
    }, batch);
}

// ---------------------------------------------------------------------------------------------
// STL input

namespace {

/// The bits of a float coordinate as a weld key: -0 is +0.
inline std::uint32_t keyBits(std::uint32_t b) { return b == 0x80000000u ? 0u : b; }

/// A 32-bit mix of three words (the finaliser of MurmurHash3 on a multiply-xor combination).
inline std::uint32_t mixKey(const std::uint32_t* k) {
    std::uint32_t h = k[0] * 0x9e3779b1u ^ k[1] * 0x85ebca77u ^ k[2] * 0xc2b2ae3du;
    h ^= h >> 16;
    h *= 0x85ebca6bu;
    h ^= h >> 13;
    h *= 0xc2b2ae35u;
    return h ^ (h >> 16);
}

/// The mesh of `count` corners, three a triangle; `cornerBits(i, bits)` gives corner i's
/// coordinates as float bits. Corners with bit-identical coordinates (+0 and -0 alike) become one
/// vertex, numbered in the order they first appear and placed at that first corner, so a closed
/// STL gives a closed mesh. A triangle that float rounding collapsed (two corners one vertex) adds
/// nothing to a closed surface and is dropped.
///
/// The corners are looked up in order in a hash table of the vertices (open addressing, linear
/// probing, at most half full), each corner's slot fetched a few corners ahead. The table touches
/// each corner once, where a sort of the corners moves each several times: on one thread it is
/// faster than the sort was on two.
template <class CornerBits>
Mesh weld(std::size_t count, const CornerBits& cornerBits) {
    if (count > std::numeric_limits<std::uint32_t>::max())
        throw Error("an STL of " + std::to_string(count / 3) + " triangles is more than a mesh can index");
    constexpr std::uint32_t kEmpty = ~0u;
    constexpr std::size_t kAhead = 8;
    Mesh mesh;
    // A closed mesh has about one vertex for six corners; the table doubles when half full.
    std::size_t capacity = 16;
    while (capacity < count / 3) capacity *= 2;
    std::vector<std::uint32_t> table, keys;  // keys: three words a vertex
    auto rebuild = [&](std::size_t size) {
        capacity = size;
        detail::reservePopulated(table, capacity);
        table.assign(capacity, kEmpty);
        for (std::uint32_t v = 0; v < keys.size() / 3; ++v) {
            std::size_t slot = mixKey(&keys[3 * std::size_t(v)]) & (capacity - 1);
            while (table[slot] != kEmpty) slot = (slot + 1) & (capacity - 1);
            table[slot] = v;
        }
    };
    rebuild(capacity);
    detail::reservePopulated(keys, 3 * (count / 6 + 16));
    detail::reservePopulated(mesh.vertices, count / 6 + 16);
    detail::reservePopulated(mesh.triangles, count / 3);
    auto keyOf = [&](std::size_t i, std::uint32_t* bits, std::uint32_t* key) {
        cornerBits(i, bits);
        for (int k = 0; k < 3; ++k) key[k] = keyBits(bits[k]);
    };
    for (std::size_t t = 0; 3 * t < count; ++t) {
        Mesh::Triangle tri{};
        for (std::size_t c = 0; c < 3; ++c) {
            const std::size_t i = 3 * t + c;
            std::uint32_t bits[3], key[3];
            if (i + kAhead < count) {
                keyOf(i + kAhead, bits, key);
                __builtin_prefetch(&table[mixKey(key) & (capacity - 1)]);
            }
            keyOf(i, bits, key);
            std::size_t slot = mixKey(key) & (capacity - 1);
            std::uint32_t v;
            while ((v = table[slot]) != kEmpty && std::memcmp(&keys[3 * std::size_t(v)], key, 12) != 0)
                slot = (slot + 1) & (capacity - 1);
            if (v == kEmpty) {
                v = std::uint32_t(mesh.vertices.size());
                table[slot] = v;
                keys.insert(keys.end(), key, key + 3);
                float xyz[3];
                std::memcpy(xyz, bits, 12);
                mesh.vertices.emplace_back(xyz[0], xyz[1], xyz[2]);
                if (2 * mesh.vertices.size() > capacity) rebuild(2 * capacity);
            }
            tri[c] = v;
        }
        if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) continue;
        mesh.triangles.push_back(tri);
    }
    return mesh;
}

/// Whether the bytes where a binary STL keeps its triangle count and its first record (offsets
/// 80 to 134) are text: printable or white space. Binary data almost never is: a count below
/// 2^24 has a zero byte, and so has a zero coordinate or normal.
bool looksLikeText(const char* data, std::size_t size) {
    for (std::size_t i = 80; i < std::min<std::size_t>(size, 134); ++i) {
        const auto c = static_cast<unsigned char>(data[i]);
        if (c < 0x20 && c != '\t' && c != '\n' && c != '\r' && c != '\f' && c != '\v') return false;
        if (c == 0x7f) return false;
    }
    return true;
}

/// A binary STL's corners, read in place from its records (50 bytes each after an 84-byte head).
Mesh parseBinaryStl(const char* data, std::uint32_t count, const std::string& path) {
    return weld(3 * std::size_t(count), [&](std::size_t i, std::uint32_t* bits) {
        const char* at = data + 84 + (i / 3) * 50 + 12 + (i % 3) * 12;
        for (int k = 0; k < 3; ++k) {
            bits[k] = binary::getU32(at + 4 * k);
            if ((bits[k] & 0x7f800000u) == 0x7f800000u)
                throw Error("'" + path + "': triangle " + std::to_string(i / 3 + 1) +
                            " has a corner that is not a finite number");
        }
    });
}

/// A whitespace tokenizer that knows the line and column of each token.
class Tokens {
public:
    Tokens(std::string_view text, std::string file) : text_(text), file_(std::move(file)) {}

    bool next() {
        while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) {
            if (text_[pos_] == '\n') {
                ++line_;
                lineStart_ = pos_ + 1;
            }
            ++pos_;
        }
        if (pos_ >= text_.size()) {
            token_.clear();
            return false;
        }
        where_ = {file_, line_, int(pos_ - lineStart_) + 1};
        const std::size_t start = pos_;
        while (pos_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[pos_])))
            ++pos_;
        token_.assign(text_.data() + start, pos_ - start);
        return true;
    }
    const std::string& token() const { return token_; }
    const SourceLocation& where() const { return where_; }

    void expect(const char* word) {
        if (!next()) throw ParseError(where_, std::string("expected '") + word + "', found the end of the file");
        if (token_ != word) throw ParseError(where_, std::string("expected '") + word + "'", token_);
    }
    float number() {
        if (!next()) throw ParseError(where_, "expected a number, found the end of the file");
        float v = 0.0f;
        const char* b = token_.data();
        const char* e = b + token_.size();
        if (*b == '+') ++b;
        const auto res = std::from_chars(b, e, v);
        if (res.ec != std::errc() || res.ptr != e || !std::isfinite(v))
            throw ParseError(where_, "expected a finite number", token_);
        return v;
    }
    /// Skips the rest of the current line (a solid's name).
    void skipLine() {
        while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    }

private:
    std::string_view text_;
    std::string file_;
    std::size_t pos_ = 0, lineStart_ = 0;
    int line_ = 1;
    std::string token_;
    SourceLocation where_;
};

Mesh parseAsciiStl(std::string_view text, const std::string& path) {
    std::vector<float> corners;
    Tokens tok(text, path);
    bool inSolid = false;
    while (tok.next()) {
        const std::string word = tok.token();
        if (word == "solid") {
            inSolid = true;
            tok.skipLine();
        } else if (word == "endsolid") {
            inSolid = false;
            tok.skipLine();
        } else if (word == "facet" && inSolid) {
            tok.expect("normal");
            for (int k = 0; k < 3; ++k) tok.number();
            tok.expect("outer");
            tok.expect("loop");
            for (int i = 0; i < 3; ++i) {
                tok.expect("vertex");
                for (int k = 0; k < 3; ++k) corners.push_back(tok.number());
            }
            tok.expect("endloop");
            tok.expect("endfacet");
        } else {
            throw ParseError(tok.where(),
                             inSolid ? "expected 'facet' or 'endsolid'" : "expected 'solid'", word);
        }
    }
    if (inSolid) throw ParseError(tok.where(), "missing 'endsolid' at the end of the file");
    return weld(corners.size() / 3, [&](std::size_t i, std::uint32_t* bits) { std::memcpy(bits, &corners[3 * i], 12); });
}

}  // namespace

Mesh readStl(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw Error("cannot read '" + path + "': it is a folder");
    errno = 0;
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot open '" + path + "'" + (errno != 0 ? std::string(": ") + std::strerror(errno) : ""));
    // A file in one read, into pages faulted in at once; a pipe as it comes.
    std::vector<char, NoZeroAllocator<char>> data;
    const bool regular = std::filesystem::is_regular_file(path, ec);
    if (regular) {
        const std::size_t size = std::size_t(std::filesystem::file_size(path, ec));
        if (!ec) detail::reservePopulated(data, size);
        data.resize(size);
        if (ec || !in.read(data.data(), std::streamsize(data.size()))) throw Error("cannot read '" + path + "'");
    } else {
        data.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
        if (in.bad()) throw Error("cannot read '" + path + "'");
    }
    Mesh mesh;
    const std::uint64_t binaryBytes = data.size() >= 84 ? 84 + 50 * std::uint64_t(binary::getU32(data.data() + 80)) : 0;
    if (data.size() >= 84 && data.size() == binaryBytes) {
        mesh = parseBinaryStl(data.data(), binary::getU32(data.data() + 80), path);
    } else {
        try {
            mesh = parseAsciiStl(std::string_view(data.data(), data.size()), path);
        } catch (const Error&) {
            // Not text either. Binary data of the wrong length is most often a file cut short,
            // which the text reader would only say does not begin with "solid".
            if (data.size() < 84 || looksLikeText(data.data(), data.size())) throw;
            throw Error("'" + path + "': a binary STL whose header counts " +
                        std::to_string(binary::getU32(data.data() + 80)) + " triangles is " +
                        std::to_string(binaryBytes) + " bytes long, and this file has " +
                        std::to_string(data.size()) + ": it is cut short, has bytes after its last triangle, or is not an STL");
        }
    }
    if (mesh.triangles.empty()) throw Error("'" + path + "' holds no triangle");
    return mesh;
}

}  // namespace dexelmill
