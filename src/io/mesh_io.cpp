#include "dexelmill/io/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <tuple>
#include <vector>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "dexelmill/error.h"
#include "dexelmill/io/atomic_file.h"
#include "io/detail/binary.h"

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

void requireValidIndices(const Mesh& mesh) {
    for (const Mesh::Triangle& t : mesh.triangles)
        for (std::uint32_t i : t)
            if (i >= mesh.vertices.size()) throw Error("mesh has a vertex index past its vertex list");
}

}  // namespace

void writeObj(const std::string& path, const Mesh& mesh) {
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
    });
}

void writeStl(const std::string& path, const Mesh& mesh) {
    requireValidIndices(mesh);
    if (mesh.triangles.size() > std::numeric_limits<std::uint32_t>::max())
        throw Error("binary STL holds at most 2^32 - 1 triangles");
    writeStreamAtomically(path, [&](std::ostream& out) {
        BlockWriter w(out);
        char header[80] = {};
        std::snprintf(header, sizeof(header), "dexelmill binary STL, mm");
        w.put(header, sizeof(header));
        char rec[50];
        binary::putU32(rec, std::uint32_t(mesh.triangles.size()));
        w.put(rec, 4);
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
            const Vec3 a = mesh.areaVector(t);
            const double len = glm::length(a);
            const Vec3 n = len > 0.0 ? a / len : Vec3(0.0);
            char* p = rec;
            for (int k = 0; k < 3; ++k) p = binary::putF32(p, float(n[k]));
            for (std::uint32_t vi : mesh.triangles[t])
                for (int k = 0; k < 3; ++k) p = binary::putF32(p, float(mesh.vertices[vi][k]));
            p[0] = p[1] = 0;
            w.put(rec, sizeof(rec));
        }
        w.flush();
    });
}

void writePly(const std::string& path, const Mesh& mesh, const PlyVertexData& data) {
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
    });
}

// ---------------------------------------------------------------------------------------------
// STL input

namespace {

/// The mesh of triangles given by their corners (nine floats a triangle): corners with
/// bit-identical coordinates (+0 and -0 alike) become one vertex, numbered in the order they first
/// appear, so a closed STL gives a closed mesh. A triangle that float rounding collapsed (two
/// corners one vertex) adds nothing to a closed surface and is dropped. The corners are sorted by
/// their bits (and their place, so each run of equal ones starts with its first appearance), which
/// scales on threads where a hash table does not.
Mesh weld(const std::vector<float>& corners) {
    const std::size_t count = corners.size() / 3;
    if (count > std::numeric_limits<std::uint32_t>::max())
        throw Error("an STL of " + std::to_string(count / 3) + " triangles is more than a mesh can index");
    struct Corner {
        std::uint32_t bits[3];
        std::uint32_t index;
        bool operator<(const Corner& o) const {
            return std::tie(bits[0], bits[1], bits[2], index) < std::tie(o.bits[0], o.bits[1], o.bits[2], o.index);
        }
    };
    std::vector<Corner> sorted(count);
    tbb::parallel_for(std::size_t(0), count, [&](std::size_t i) {
        Corner& c = sorted[i];
        std::memcpy(c.bits, &corners[3 * i], 12);
        for (std::uint32_t& b : c.bits)
            if (b == 0x80000000u) b = 0;  // -0 is +0
        c.index = std::uint32_t(i);
    });
    tbb::parallel_sort(sorted.begin(), sorted.end());
    // Each corner's run, and each run's first corner.
    std::vector<std::uint32_t> run(count), first;
    for (std::size_t k = 0; k < count; ++k) {
        const bool starts = k == 0 || std::memcmp(sorted[k].bits, sorted[k - 1].bits, 12) != 0;
        if (starts) first.push_back(sorted[k].index);
        run[sorted[k].index] = std::uint32_t(first.size() - 1);
    }
    std::vector<Corner>().swap(sorted);
    // Vertices numbered as their runs first appear.
    Mesh mesh;
    std::vector<std::uint32_t> vertexOf(first.size());
    mesh.vertices.reserve(first.size());
    for (std::size_t i = 0; i < count; ++i)
        if (first[run[i]] == i) {
            vertexOf[run[i]] = std::uint32_t(mesh.vertices.size());
            mesh.vertices.emplace_back(corners[3 * i], corners[3 * i + 1], corners[3 * i + 2]);
        }
    mesh.triangles.reserve(count / 3);
    for (std::size_t t = 0; t < count / 3; ++t) {
        const Mesh::Triangle tri{vertexOf[run[3 * t]], vertexOf[run[3 * t + 1]], vertexOf[run[3 * t + 2]]};
        if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) continue;
        mesh.triangles.push_back(tri);
    }
    return mesh;
}

Mesh parseBinaryStl(const std::string& data, std::uint32_t count, const std::string& path) {
    std::vector<float> corners(9 * std::size_t(count));
    tbb::parallel_for(std::size_t(0), std::size_t(count), [&](std::size_t t) {
        const char* rec = data.data() + 84 + t * 50;
        for (std::size_t k = 0; k < 9; ++k) corners[9 * t + k] = binary::getF32(rec + 12 + 4 * k);
    });
    const auto bad = std::find_if(corners.begin(), corners.end(), [](float v) { return !std::isfinite(v); });
    if (bad != corners.end())
        throw Error("'" + path + "': triangle " + std::to_string((bad - corners.begin()) / 9 + 1) +
                    " has a corner that is not a finite number");
    return weld(corners);
}

/// A whitespace tokenizer that knows the line and column of each token.
class Tokens {
public:
    Tokens(const std::string& text, std::string file) : text_(text), file_(std::move(file)) {}

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
        token_.assign(text_, start, pos_ - start);
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
    const std::string& text_;
    std::string file_;
    std::size_t pos_ = 0, lineStart_ = 0;
    int line_ = 1;
    std::string token_;
    SourceLocation where_;
};

Mesh parseAsciiStl(const std::string& text, const std::string& path) {
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
    return weld(corners);
}

}  // namespace

Mesh readStl(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw Error("cannot read '" + path + "': it is a folder");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot open '" + path + "'");
    // A file in one read; a pipe as it comes.
    std::string data;
    const bool regular = std::filesystem::is_regular_file(path, ec);
    if (regular) {
        data.resize(std::size_t(std::filesystem::file_size(path, ec)));
        if (ec || !in.read(data.data(), std::streamsize(data.size()))) throw Error("cannot read '" + path + "'");
    } else {
        data.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
        if (in.bad()) throw Error("cannot read '" + path + "'");
    }
    Mesh mesh;
    if (data.size() >= 84 &&
        data.size() == 84 + 50 * std::uint64_t(binary::getU32(data.data() + 80))) {
        mesh = parseBinaryStl(data, binary::getU32(data.data() + 80), path);
    } else {
        mesh = parseAsciiStl(data, path);
    }
    if (mesh.triangles.empty()) throw Error("'" + path + "' holds no triangle");
    return mesh;
}

}  // namespace dexelmill
