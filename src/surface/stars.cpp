#include "surface/stars.h"

#include <algorithm>
#include <limits>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "memory/pages.h"

namespace dexelmill::detail {

namespace {

/// The stars of the vertices first .. first + offset.size() - 2 from triangles [tlo, thi), in
/// one scan: the corners at those vertices are gathered with their vertex (in `found`), counted,
/// then placed in the order found, which is triangle order.
void sortCorners(const Mesh& mesh, std::size_t tlo, std::size_t thi, Stars& s, std::vector<std::uint64_t>& found) {
    const std::uint32_t n = std::uint32_t(s.offset.size() - 1);
    found.clear();
    for (std::size_t t = tlo; t < thi; ++t)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t i = mesh.triangles[t][std::size_t(k)] - s.first;
            if (i < n) {
                found.push_back(std::uint64_t(i) << 32 | (3 * t + std::size_t(k)));
                ++s.offset[i + 1];
            }
        }
    for (std::uint32_t i = 0; i < n; ++i) s.offset[i + 1] += s.offset[i];
    s.corners.resize(s.offset[n]);
    // offset[i] serves as vertex i's cursor, ending at vertex i + 1's start; shifted back after.
    for (std::uint64_t f : found) s.corners[s.offset[f >> 32]++] = std::uint32_t(f);
    for (std::uint32_t i = n; i > 0; --i) s.offset[i] = s.offset[i - 1];
    s.offset[0] = 0;
}

/// Per run of `size` consecutive vertices: the first triangle and one past the last with a
/// corner at one of them (lo > hi where none has), found by parts of the triangle list side by
/// side.
void stretches(const Mesh& mesh, std::uint32_t size, std::vector<std::uint32_t>& lo, std::vector<std::uint32_t>& hi) {
    const std::size_t runs = (mesh.vertices.size() + size - 1) / size, nt = mesh.triangles.size();
    const std::size_t parts = std::size_t(std::max(1, tbb::this_task_arena::max_concurrency()));
    std::vector<std::vector<std::uint32_t>> partLo(parts), partHi(parts);
    tbb::parallel_for(std::size_t(0), parts, [&](std::size_t p) {
        std::vector<std::uint32_t>& l = partLo[p];
        std::vector<std::uint32_t>& h = partHi[p];
        l.assign(runs, std::numeric_limits<std::uint32_t>::max());
        h.assign(runs, 0);
        for (std::size_t t = nt * p / parts; t < nt * (p + 1) / parts; ++t)
            for (std::uint32_t v : mesh.triangles[t]) {
                const std::size_t r = v / size;
                l[r] = std::min(l[r], std::uint32_t(t));
                h[r] = std::max(h[r], std::uint32_t(t + 1));
            }
    });
    lo.assign(runs, std::numeric_limits<std::uint32_t>::max());
    hi.assign(runs, 0);
    for (std::size_t p = 0; p < parts; ++p)
        for (std::size_t r = 0; r < runs; ++r) {
            lo[r] = std::min(lo[r], partLo[p][r]);
            hi[r] = std::max(hi[r], partHi[p][r]);
        }
}

/// Builds the stars of vertices first .. first + count - 1 from triangles [lo, hi).
void buildRun(const Mesh& mesh, std::uint32_t first, std::size_t count, std::uint32_t lo, std::uint32_t hi, Stars& out,
              std::vector<std::uint64_t>& scratch) {
    out.first = first;
    out.offset.assign(count + 1, 0);
    out.corners.clear();
    if (hi > lo) sortCorners(mesh, lo, hi, out, scratch);
}

}  // namespace

Stars buildStars(const Mesh& mesh) {
    const std::size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
    Stars s;
    reservePopulated(s.offset, nv + 1);
    reservePopulated(s.corners, 3 * nt);
    s.offset.assign(nv + 1, 0);
    // A counting sort in triangle order, split by vertex range: each part scans every triangle
    // and takes the corners of its own vertices. Each star comes out sorted, with no atomics,
    // the same for any thread count. (Atomic counters over all vertices, then a sort of each
    // star, took twice as long on two threads: the scans are sequential, the counters not.)
    const std::size_t parts = std::size_t(std::max(1, tbb::this_task_arena::max_concurrency()));
    auto partStart = [&](std::size_t p) { return std::uint32_t(nv * p / parts); };
    tbb::parallel_for(std::size_t(0), parts, [&](std::size_t p) {
        const std::uint32_t lo = partStart(p), hi = partStart(p + 1);
        for (const Mesh::Triangle& t : mesh.triangles)
            for (std::uint32_t v : t)
                if (v >= lo && v < hi) ++s.offset[v + 1];
    });
    for (std::size_t v = 0; v < nv; ++v) s.offset[v + 1] += s.offset[v];
    s.corners.resize(s.offset[nv]);
    tbb::parallel_for(std::size_t(0), parts, [&](std::size_t p) {
        const std::uint32_t lo = partStart(p), hi = partStart(p + 1);
        std::vector<std::uint32_t, NoZeroAllocator<std::uint32_t>> cursor(s.offset.begin() + lo, s.offset.begin() + hi);
        for (std::size_t t = 0; t < nt; ++t)
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t v = mesh.triangles[t][std::size_t(k)];
                if (v >= lo && v < hi) s.corners[cursor[v - lo]++] = std::uint32_t(3 * t + std::size_t(k));
            }
    });
    return s;
}

StarChunks::StarChunks(const Mesh& mesh, std::size_t chunkedBytes) : mesh_(mesh) {
    const std::size_t nt = mesh.triangles.size();
    if (3 * nt * sizeof(std::uint32_t) >= chunkedBytes) {
        stretches(mesh, kPiece, pieceLo_, pieceHi_);
        // A chunk's stretch spans its pieces'.
        constexpr std::uint32_t kPiecesPerChunk = kChunk / kPiece;
        const std::size_t chunks = (pieceLo_.size() + kPiecesPerChunk - 1) / kPiecesPerChunk;
        lo_.assign(chunks, std::numeric_limits<std::uint32_t>::max());
        hi_.assign(chunks, 0);
        for (std::size_t p = 0; p < pieceLo_.size(); ++p) {
            lo_[p / kPiecesPerChunk] = std::min(lo_[p / kPiecesPerChunk], pieceLo_[p]);
            hi_[p / kPiecesPerChunk] = std::max(hi_[p / kPiecesPerChunk], pieceHi_[p]);
        }
        double scanned = 0.0;
        for (std::size_t c = 0; c < chunks; ++c)
            if (hi_[c] > lo_[c]) scanned += double(hi_[c] - lo_[c]);
        if (scanned <= kMaxScans * double(nt)) return;
    }
    whole_ = std::make_unique<Stars>(buildStars(mesh));
    lo_.clear();
    hi_.clear();
    pieceLo_.clear();
    pieceHi_.clear();
}

void StarChunks::build(std::size_t c, Stars& out, std::vector<std::uint64_t>& scratch) const {
    const auto first = std::uint32_t(c * kChunk);
    buildRun(mesh_, first, std::min<std::size_t>(kChunk, mesh_.vertices.size() - first), lo_[c], hi_[c], out, scratch);
}

const Stars& StarChunks::stars(std::uint32_t v) const {
    if (whole_) return *whole_;
    const std::size_t p = v / kPiece;
    auto it = cache_.find(p);
    if (it == cache_.end()) {
        it = cache_.emplace(p, Stars{}).first;
        const auto first = std::uint32_t(p * kPiece);
        buildRun(mesh_, first, std::min<std::size_t>(kPiece, mesh_.vertices.size() - first), pieceLo_[p], pieceHi_[p],
                 it->second, scratch_);
    }
    return it->second;
}

}  // namespace dexelmill::detail
