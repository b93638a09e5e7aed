// The design part: its cast on the lattice and its exact distance (MeshDistance).
#include "dexelmill/compare/design.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>

#include <tbb/blocked_range.h>
#include <tbb/collaborative_call_once.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "dexelmill/error.h"
#include "dexelmill/io/file_name.h"
#include "dexelmill/io/mesh_io.h"
#include "dexelmill/io/vdb_io.h"
#include "dexelmill/surface/levelset.h"
#include "compare/detail/deepest.h"

namespace dexelmill {

namespace {

/// The depth search stops when no point can lie deeper than the deepest found by more than a
/// quarter of the tolerance or this fraction of the spacing, whichever is less, but not below
/// kMinDepthBound (mm).
constexpr double kSpacingBound = 0.01;
constexpr double kMinDepthBound = 1e-4;

/// A float's rounding is 6e-8 of its value; a stated stock may be this much (relative to the
/// design's largest coordinate) smaller than an STL design's box and still hold it.
constexpr double kFloatSlack = 1e-6;

/// The grid a local index (DesignPart::distanceNear) sorts its boxes on: this many cells along the
/// longest side of their union.
constexpr int kNearGridCells = 32;
/// Past this many grid entries a box on average, a local index is not tried.
constexpr std::size_t kNearEntriesPerBox = 64;

}  // namespace


Mesh readDesign(const std::string& path, const std::optional<Affine>& place) {
    const std::string extension = lowerExtension(path);
    if (extension != ".stl" && extension != ".vdb")
        throw Error("'" + path + "': a design must be an STL file (.stl, binary or ASCII) or a level set (.vdb)");
    if (place && !(std::abs(place->determinant()) > 0.0))
        throw Error("'" + path + "': the design transform flattens the design (its determinant is 0)");
    // A level set is measured through its zero surface, meshed at its own voxel size.
    Mesh mesh = extension == ".stl" ? readStl(path) : meshLevelSet(readVdb(path));
    if (mesh.empty()) throw Error("'" + path + "': the design has no triangles");
    if (place) {
        for (Vec3& v : mesh.vertices) v = place->apply(v);
        if (place->determinant() < 0.0)
            for (Mesh::Triangle& tri : mesh.triangles) std::swap(tri[1], tri[2]);
    }
    return mesh;
}

/// The distance index, or what builds it once.
struct DesignPart::Index {
    tbb::collaborative_once_flag once;
    /// Guards `mesh` and `built`: a local index (distanceNear) reads the mesh, which the whole
    /// index's build lets go of when it is done. Held only to copy or drop the pointer.
    std::mutex guard;
    std::shared_ptr<const Mesh> mesh;  ///< null once the index is built
    bool built = false;
    bool signs = false;
    std::unique_ptr<MeshDistance> distance;
    /// A build that failed: kept and thrown again, so the threads waiting on it and every later
    /// caller get its error rather than each building again.
    std::exception_ptr failure;
};

DesignPart::DesignPart(TriDexelStock d, Mesh mesh, std::unique_ptr<MeshDistance> distance, bool signs)
    : dexels(std::move(d)), index_(std::make_unique<Index>()) {
    index_->signs = signs;
    if (distance) {
        index_->distance = std::move(distance);
        index_->built = true;
        tbb::collaborative_call_once(index_->once, [] {});
    } else {
        index_->mesh = std::make_shared<const Mesh>(std::move(mesh));
    }
}

DesignPart::DesignPart(DesignPart&&) noexcept = default;
DesignPart& DesignPart::operator=(DesignPart&&) noexcept = default;
DesignPart::~DesignPart() = default;

const MeshDistance& DesignPart::distance() const {
    if (!index_) throw Error("the design part was moved from: it has no distance");
    Index& index = *index_;
    tbb::collaborative_call_once(index.once, [&index] {
        try {
            index.distance = std::make_unique<MeshDistance>(*index.mesh, index.signs);
            const std::lock_guard<std::mutex> lock(index.guard);
            index.mesh.reset();
            index.built = true;
        } catch (...) {
            index.failure = std::current_exception();
        }
    });
    if (index.failure) std::rethrow_exception(index.failure);
    if (!index.distance) throw Error("the design's distance was handed over");
    return *index.distance;
}

std::unique_ptr<MeshDistance> DesignPart::takeDistance() {
    distance();
    return std::move(index_->distance);
}

NearDistance DesignPart::distanceNear(const std::vector<Box>& where) const {
    if (!index_) throw Error("the design part was moved from: it has no distance");
    NearDistance near;
    auto whole = [&] {
        near.index = &distance();
        return std::move(near);
    };
    for (const Box& b : where)
        if (!std::isfinite(b.lo.x + b.lo.y + b.lo.z + b.hi.x + b.hi.y + b.hi.z)) return whole();
    std::shared_ptr<const Mesh> held;
    {
        const std::lock_guard<std::mutex> lock(index_->guard);
        if (!index_->built) held = index_->mesh;
    }
    if (!held) return whole();
    const Mesh& mesh = *held;
    // The boxes, clipped to the design's, on a coarse grid over their union: a triangle is tested
    // against the boxes of the cells its own box spans.
    const Box meshBox = mesh.bounds();
    std::vector<Box> boxes;
    Box all;
    for (const Box& b : where) {
        const Box clipped{glm::max(b.lo, meshBox.lo), glm::min(b.hi, meshBox.hi)};
        if (clipped.isEmpty()) continue;
        boxes.push_back(clipped);
        all.expand(clipped);
    }
    std::vector<std::uint8_t> chosen(mesh.triangles.size(), 0);
    if (!boxes.empty()) {
        // Cells no smaller than the median box, so that most boxes span at most two a side.
        const Vec3 size = all.size();
        std::vector<double> sides(boxes.size());
        for (std::size_t i = 0; i < boxes.size(); ++i) {
            const Vec3 b = boxes[i].size();
            sides[i] = std::max({b.x, b.y, b.z});
        }
        std::nth_element(sides.begin(), sides.begin() + std::ptrdiff_t(sides.size() / 2), sides.end());
        const double longest = std::max({size.x, size.y, size.z});
        const double cell = longest > 0.0 ? std::max(longest / kNearGridCells, sides[sides.size() / 2]) : 1.0;
        std::array<int, 3> cells{};
        for (int k = 0; k < 3; ++k) cells[std::size_t(k)] = std::clamp(int(std::ceil(size[k] / cell)), 1, kNearGridCells);
        auto cellOf = [&](int k, double at) {
            return std::clamp(int(std::floor((at - all.lo[k]) / cell)), 0, cells[std::size_t(k)] - 1);
        };
        auto flat = [&](int x, int y, int z) { return std::size_t(x) + std::size_t(cells[0]) * (std::size_t(y) + std::size_t(cells[1]) * std::size_t(z)); };
        std::vector<std::size_t> start(std::size_t(cells[0]) * std::size_t(cells[1]) * std::size_t(cells[2]) + 1, 0);
        auto eachCell = [&](const Box& b, auto&& use) {
            const int x0 = cellOf(0, b.lo.x), x1 = cellOf(0, b.hi.x), y0 = cellOf(1, b.lo.y), y1 = cellOf(1, b.hi.y),
                      z0 = cellOf(2, b.lo.z), z1 = cellOf(2, b.hi.z);
            for (int z = z0; z <= z1; ++z)
                for (int y = y0; y <= y1; ++y)
                    for (int x = x0; x <= x1; ++x) use(flat(x, y, z));
        };
        for (const Box& b : boxes) eachCell(b, [&](std::size_t c) { ++start[c + 1]; });
        for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
        // Boxes much larger than most, many of them: the whole index serves as well.
        if (start.back() > kNearEntriesPerBox * boxes.size() + start.size()) return whole();
        std::vector<std::uint32_t> listed(start.back());
        {
            std::vector<std::size_t> at(start.begin(), start.end() - 1);
            for (std::uint32_t i = 0; i < boxes.size(); ++i) eachCell(boxes[i], [&](std::size_t c) { listed[at[c]++] = i; });
        }
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.triangles.size(), 4096), [&](const auto& r) {
            for (std::size_t t = r.begin(); t != r.end(); ++t) {
                Box tb;
                for (const std::uint32_t v : mesh.triangles[t]) tb.expand(mesh.vertices[v]);
                if (!tb.overlaps(all)) continue;
                bool hit = false;
                eachCell(tb, [&](std::size_t c) {
                    for (std::size_t k = start[c]; k < start[c + 1] && !hit; ++k) hit = tb.overlaps(boxes[listed[k]]);
                });
                chosen[t] = hit;
            }
        });
    }
    const std::size_t count = std::size_t(std::count(chosen.begin(), chosen.end(), std::uint8_t(1)));
    if (double(count) > kNearShare * double(mesh.triangles.size())) return whole();
    // Those triangles, with their own vertices.
    Mesh part;
    part.triangles.reserve(count);
    std::vector<std::uint32_t> renumber(mesh.vertices.size(), ~0u);
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        if (!chosen[t]) continue;
        Mesh::Triangle tri = mesh.triangles[t];
        for (std::uint32_t& v : tri) {
            if (renumber[v] == ~0u) {
                renumber[v] = std::uint32_t(part.vertices.size());
                part.vertices.push_back(mesh.vertices[v]);
            }
            v = renumber[v];
        }
        part.triangles.push_back(tri);
    }
    held.reset();
    near.local = std::make_unique<MeshDistance>(part, false);
    near.index = near.local.get();
    return near;
}

DesignPart loadDesign(Mesh mesh, const std::string& path, const Lattice& lattice, FamilySet families, bool signs) {
    MeshCastStats cast;
    std::optional<TriDexelStock> dexels;
    std::unique_ptr<MeshDistance> distance;
    if (signs) {
        // The cast and the distance index are built side by side: each has stretches that run
        // on one thread, which the other fills.
        tbb::parallel_invoke([&] { dexels.emplace(stockFromMesh(mesh, lattice, families, &cast)); },
                             [&] { distance = std::make_unique<MeshDistance>(mesh, signs); });
    } else {
        dexels.emplace(stockFromMesh(mesh, lattice, families, &cast));
    }
    const Box bounds = mesh.bounds();
    DesignPart d(std::move(*dexels), std::move(mesh), std::move(distance), signs);
    d.cast = cast;
    d.file = path;
    d.bounds = bounds;
    if (d.dexels.volume(d.dexels.measuringFamily()) <= 0.0) {
        // An open mesh's inside is guessed from the crossings that pair up; where none do, the
        // guess is empty, which says nothing of where the design is.
        if (cast.unpairedDexels > 0)
            throw Error("'" + path + "': the design is not closed (" + std::to_string(cast.unpairedDexels) +
                        " dexel lines meet an odd number of its faces), so what it holds cannot be told: cast on the "
                        "lattice it holds no material; close the mesh, or measure a part against its surface with "
                        "'dexelmill compare', which needs no inside");
        throw Error("'" + path + "': the design holds no material inside the stock's box");
    }
    return d;
}

DesignPart loadDesign(const std::string& path, const Lattice& lattice, FamilySet families) {
    return loadDesign(readDesign(path), path, lattice, families);
}

Box designStockBox(const Box& design, const std::optional<StatedStock>& stated, std::string& note) {
    char text[400];
    if (!stated) {
        std::snprintf(text, sizeof text,
                      "no --stock: the stock is the design's bounding box, x %g .. %g, y %g .. %g, z %g .. %g mm",
                      design.lo.x, design.hi.x, design.lo.y, design.hi.y, design.lo.z, design.hi.z);
        note = text;
        return design;
    }
    const Vec3 need = design.size(), size = stated->size;
    // STL stores single floats: the design's box is known to a few float roundings of its largest
    // coordinate.
    const double slack = kFloatSlack * std::max({glm::length(design.lo), glm::length(design.hi), 1.0});
    for (int k = 0; k < 3; ++k)
        if (size[k] < need[k] - slack) {
            std::snprintf(text, sizeof text,
                          "%s:%d: the stated stock (%g x %g x %g mm) is smaller than the design (%g x %g x %g mm) "
                          "along %c: give --stock",
                          stated->where.file.c_str(), stated->where.line, size.x, size.y, size.z, need.x, need.y,
                          need.z, "xyz"[k]);
            throw Error(text);
        }
    Box box;
    const Vec3 c = design.center();
    box.lo.x = c.x - 0.5 * size.x, box.hi.x = c.x + 0.5 * size.x;
    box.lo.y = c.y - 0.5 * size.y, box.hi.y = c.y + 0.5 * size.y;
    const bool topAtZero = design.hi.z <= slack && design.lo.z >= -size.z - slack;
    box.hi.z = topAtZero ? 0.0 : design.lo.z + size.z;
    box.lo.z = box.hi.z - size.z;
    std::snprintf(text, sizeof text,
                  "no --stock: the stock is the %g x %g x %g mm the program states (%s:%d), around the design: "
                  "x %g .. %g, y %g .. %g, z %g .. %g mm (%s)",
                  size.x, size.y, size.z, stated->where.file.c_str(), stated->where.line, box.lo.x, box.hi.x,
                  box.lo.y, box.hi.y, box.lo.z, box.hi.z,
                  topAtZero ? "top at z = 0" : "bottom on the design's bottom");
    note = text;
    return box;
}

double depthBound(double tolerance, double h) {
    return std::max(kMinDepthBound, std::min(0.25 * tolerance, kSpacingBound * h));
}

std::vector<Gouge> findGouges(const DesignPart& design, const Lattice& lattice, const CutResult& cut, double tolerance) {
    const std::vector<DesignStretch>& stretches = cut.designStretches;
    // The stretches come in move order: one group per move.
    std::vector<std::size_t> groups;
    for (std::size_t i = 0; i < stretches.size(); ++i)
        if (i == 0 || stretches[i].move != stretches[i - 1].move) groups.push_back(i);
    groups.push_back(stretches.size());
    const double eps = depthBound(tolerance, lattice.h);
    // Each stretch lies within its reach of the design's surface: the ends of the design's segment
    // along the dexel. Its own ends are floats, each within `rounding` of the end of the cut it
    // stores, so its points' depths are within `rounding` of those of the cut along the dexel.
    const double rounding = endRounding(lattice);
    std::vector<DexelStretch> lines(stretches.size());
    for (std::size_t i = 0; i < stretches.size(); ++i) {
        const DesignStretch& s = stretches[i];
        lines[i] = {s.family, s.ib, s.ic, double(s.lo), double(s.hi), s.reach + rounding};
    }
    const std::vector<Deepest> deepest = deepestPoints(design, lattice, lines, groups, eps);
    // Volumes as the report measures them: the z family's, else x's, else y's.
    const Axis measure = design.dexels.measuringFamily();
    std::vector<Gouge> gouges;
    for (std::size_t g = 0; g + 1 < groups.size(); ++g) {
        // A cut at most `tolerance` deep has stretches at most `rounding` deeper.
        if (!(deepest[g].depth > tolerance + rounding)) continue;
        Gouge gouge;
        gouge.move = stretches[groups[g]].move;
        gouge.depth = deepest[g].depth;
        gouge.point = deepest[g].point;
        gouge.volume = cut.moves[gouge.move].designRemoved[std::size_t(index(measure))];
        gouges.push_back(gouge);
    }
    return gouges;
}

}  // namespace dexelmill
