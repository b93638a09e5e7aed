#include "dexelmill/refine/refine.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "dexelmill/surface/simplify.h"
#include "memory/pages.h"
#include "surface/detail/crossings.h"
#include "refine/detail/edge_table.h"
#include "refine/detail/pieces.h"
#include "refine/detail/windows.h"

namespace dexelmill {

namespace {

using detail::EdgeTable;
using detail::kNoTriangle;
using detail::Local;

/// Rings around a fold within which the snapped vertices go back, at most.
constexpr int kSnapRings = 3;
/// A vertex is moved along an axis other than the nearest to its normal only within 75 degrees
/// of the normal (cos 75 = 0.2588). The crossing on an axis at angle a from the surface's normal
/// moves 1 / cos a times as far as the surface does, and slides the vertex across it by tan a
/// times what it brings it closer (3.7 at 75 degrees): nearer the tangent, a small error in the
/// mesher's normal sends the vertex far along the surface. (Measured on scorpion's walls about h
/// thick, `--refine 1`: 4 misses of the measure instead of 8 without this limit; bear's largest
/// face offset 0.20 h instead of 0.19 h.)
constexpr double kLaterAxisCosine = 0.2588;

/// A crossing farther from a midpoint than this fraction of its edge's length, or from a vertex
/// than this fraction of its longest edge, is asked again along the other axes within 75 degrees
/// of the normal, and the nearest inward is kept (takeNearerAlongLaterAxes): a
/// window along an axis nearly tangent to the part slides along it. On a smooth part the midpoint
/// of an edge whose ends lie on it is off by about L^2 k / 8 (k the curvature across the edge);
/// at bear's grid that is under 0.02 L for its 1.59 mm ball, so only edges across creases, and
/// windows sliding along the part, pass it.
constexpr double kSlidFraction = 0.1;

/// After the rounds, edges shorter than this fraction of the window (a sixteenth of a spacing)
/// are collapsed (collapseShortEdges): the surface moves by less than that, and its vertices stay
/// on the part. A split next to a vertex, such as a crossing whose dexel grazes the part, leaves
/// pieces a few micrometres across that face every way, and a measure along their normals finds
/// no surface: bear, `--refine 1`, at (24.32, 60.47, -11.60), two splits 0.011 mm from a crossing
/// on a y dexel left triangles 90 degrees off the part's slope, measured 3 h off (a miss).
constexpr double kShortEdge = 0.125;

/// A vertex whose windows found no crossing on any axis is asked along the nearest axis this many
/// windows far (a spacing, with the default window of half a spacing). A wedge thinner than the
/// spacing whose tip reaches past a lattice line has no crossing on that line's dexels, and the
/// mesher ends it at the last line that saw it: scorpion, `--refine 1`, at (133.80, 110.34), a
/// tip 0.16 mm beyond the line y = 110.321 was cut off, and the faces there measured 0.34 h.
/// Only the nearest axis is asked, so the move follows the vertex's normal, outward or inward.
constexpr double kFarReach = 2.0;

/// A vertex whose every move onto the part folded the mesh, or passed a triangle through another,
/// is moved this fraction of its shortest move, then its square, and so on for kPartialTries
/// tries; the first that does not fold is kept, and the vertex lies that much nearer the part.
/// The mesher puts a sharp edge's vertex where the planes of its crossings meet; a cusp the
/// lattice did not see may have lowered that edge past the crossings beside it, and a move onto
/// the part then passes the vertex below them. (Bear, `--refine 1`, the top of a wall at
/// (60.17, 25.92, -4.17): the vertex lay 0.069 mm, 0.23 h, above the part along z, the move
/// folded, and the triangles round it stood out of the part so far that a measure along their
/// normals found no surface within 3 h.)
constexpr double kPartialMove = 0.5;
constexpr int kPartialTries = 3;

/// Pieces that pass through another triangle by more than this (mm) are refused as folds are
/// (detail::crossingTriangles): far below the sweep's accuracy of 1e-6 mm, far above rounding.
constexpr double kCrossingTolerance = 1e-9;

/// Whether a move of `offset` along `axis` takes a vertex with (outward) normal n into the
/// material: the surface found lies behind the vertex, which the mesher put outside the part.
/// Only such moves are made along axes other than the nearest. A vertex outside sits on a corner
/// that a cut the lattice did not see has taken away (bear's wall tops), and moving it in is what
/// the later axes are for. A vertex inside the material lies in a wall thinner than the lattice
/// showed, which the mesher crossed with a face: moved out onto the wall's side along another
/// axis, it stands its triangles along the wall, facing no surface. (Scorpion, `--refine 1`: with
/// outward moves too, 12 of the measure's points found no surface within 3 h and its face RMS was
/// 0.035 h; without them none and 0.016 h. Bear's largest face offset went from 0.175 to 0.156 h.)
bool inward(const Vec3& n, int axis, double offset) { return offset * n[axis] < 0.0; }

Vec3 unit(const Vec3& v) {
    const double n = glm::length(v);
    return n > 0.0 ? v / n : Vec3(0.0);
}

/// The longest edge of the mesh (mm).
double longestEdge(const Mesh& mesh) {
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, mesh.triangles.size()), 0.0,
        [&](const tbb::blocked_range<std::size_t>& r, double m) {
            for (std::size_t t = r.begin(); t < r.end(); ++t)
                for (int k = 0; k < 3; ++k)
                    m = std::max(m, glm::length(mesh.vertices[mesh.triangles[t][(k + 1) % 3]] -
                                                mesh.vertices[mesh.triangles[t][k]]));
            return m;
        },
        [](double a, double b) { return std::max(a, b); });
}

/// The triangles of `mesh` with a corner some sweep may come near (`cells`): the only ones whose
/// edges can be off the stock box's faces, where the mesher is exact. The cells' margin is at
/// least half the longest edge beyond the windows' reach, so an edge whose midpoint window a sweep
/// reaches has both its triangles here.
std::vector<std::uint32_t> activeTriangles(const Mesh& mesh, const detail::SweptCells& cells) {
    std::vector<char> reached;
    detail::reservePopulated(reached, mesh.vertices.size());
    reached.resize(mesh.vertices.size());
    tbb::parallel_for(std::size_t(0), mesh.vertices.size(),
                      [&](std::size_t v) { reached[v] = cells.reached(mesh.vertices[v]); });
    std::vector<std::uint32_t> active;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const Mesh::Triangle& tri = mesh.triangles[t];
        if (reached[tri[0]] || reached[tri[1]] || reached[tri[2]]) active.push_back(std::uint32_t(t));
    }
    return active;
}

/// The offsets along their axes from the windows' points to the exact part's surface facing their
/// way (NaN where there is none within `reach`, by default the options' window): windows no sweep
/// comes near (`cells`) find the stock box alone and are answered here; the others are cut by the
/// moves.
std::vector<double> exactOffsets(const std::vector<detail::Window>& windows, const detail::SweptCells& cells,
                                 const Box& stock, const ToolPath& path, const ToolTable& tools,
                                 const RefineOptions& o, const std::string& stage, double reach = 0.0) {
    if (!(reach > 0.0)) reach = o.window;
    std::vector<double> offsets;
    std::vector<char> nearSweep;
    detail::reservePopulated(offsets, windows.size());
    detail::reservePopulated(nearSweep, windows.size());
    offsets.assign(windows.size(), 0.0);
    nearSweep.assign(windows.size(), 0);
    tbb::parallel_for(std::size_t(0), windows.size(), [&](std::size_t i) {
        nearSweep[i] = cells.reached(windows[i].point);
        if (!nearSweep[i]) offsets[i] = detail::stockCrossing(windows[i], reach, stock);
    });
    std::vector<std::uint32_t> cutIndex;
    std::vector<detail::Window> cut;
    const std::size_t near = std::size_t(std::count(nearSweep.begin(), nearSweep.end(), 1));
    detail::reservePopulated(cutIndex, near);
    detail::reservePopulated(cut, near);
    for (std::size_t i = 0; i < windows.size(); ++i)
        if (nearSweep[i]) cutIndex.push_back(std::uint32_t(i)), cut.push_back(windows[i]);
    std::function<void(std::size_t, std::size_t)> progress;
    if (o.progress) progress = [&](std::size_t done, std::size_t total) { o.progress(stage.c_str(), done, total); };
    const std::vector<double> exact = detail::exactCrossings(cut, reach, stock, path, tools, o.removeShankMaterial,
                                                               o.turnTolerance, progress);
    for (std::size_t k = 0; k < cutIndex.size(); ++k) offsets[cutIndex[k]] = exact[k];
    return offsets;
}

/// The window along the coordinate axis that is `rank`-th nearest `normal` (0: the nearest),
/// facing its way; false if the normal has no direction, or if a later axis lies farther than
/// kLaterAxisCosine allows.
bool windowAlong(const Vec3& point, const Vec3& normal, int rank, detail::Window& w) {
    std::array<int, 3> axes{0, 1, 2};
    std::stable_sort(axes.begin(), axes.end(), [&](int a, int b) { return std::abs(normal[a]) > std::abs(normal[b]); });
    const int axis = axes[std::size_t(rank)];
    if (!(std::abs(normal[axes[0]]) > 0.0)) return false;
    if (rank > 0 && !(std::abs(normal[axis]) >= kLaterAxisCosine * glm::length(normal))) return false;
    w.point = point;
    w.axis = axis;
    w.outward = normal[axis] > 0.0;
    return true;
}

/// The windows of the items in `asked`, built in parallel: `along(item, point, normal)` gives each
/// item's point and normal. Items whose normal has no direction are dropped from `asked`, so the
/// two lists stay in step. The windows run along each normal's `rank`-th nearest axis (windowAlong).
template <class Along>
std::vector<detail::Window> windowsFor(std::vector<std::uint32_t>& asked, const Along& along, int rank = 0) {
    std::vector<detail::Window> windows;
    std::vector<char> facing;
    detail::reservePopulated(windows, asked.size());
    detail::reservePopulated(facing, asked.size());
    windows.resize(asked.size());
    facing.assign(asked.size(), 0);
    tbb::parallel_for(std::size_t(0), asked.size(), [&](std::size_t i) {
        Vec3 point(0.0), normal(0.0);
        along(asked[i], point, normal);
        facing[i] = windowAlong(point, normal, rank, windows[i]);
    });
    std::size_t kept = 0;
    for (std::size_t i = 0; i < asked.size(); ++i)
        if (facing[i]) asked[kept] = asked[i], windows[kept] = windows[i], ++kept;
    asked.resize(kept);
    windows.resize(kept);
    return windows;
}

/// The windows of `items` along their normals' second and third nearest axes, those within 75
/// degrees of the normal (windowsFor ranks 1 and 2, one list: the cut's set-up over every move
/// is paid once); owner[k] is the item of window k.
template <class Along>
std::vector<detail::Window> laterAxesWindows(const std::vector<std::uint32_t>& items, const Along& along,
                                             std::vector<std::uint32_t>& owner) {
    std::vector<detail::Window> all;
    owner.clear();
    for (int rank = 1; rank < 3; ++rank) {
        std::vector<std::uint32_t> kept = items;
        const std::vector<detail::Window> windows = windowsFor(kept, along, rank);
        all.insert(all.end(), windows.begin(), windows.end());
        owner.insert(owner.end(), kept.begin(), kept.end());
    }
    return all;
}

/// Asks the windows of the items `far` (indices into `windows` and `offsets`) again along their
/// later axes (laterAxesWindows), and where one finds a crossing nearer than the first, or the
/// first found none, and reaching it takes the point into the material (inward), puts that window
/// and offset in place of the first (kSlidFraction). `along(i, point, normal)` gives item i's
/// point and normal, `cut(windows)` the windows' offsets. Returns the number of items changed;
/// `queries` counts the windows asked.
template <class Along, class Cut>
std::size_t takeNearerAlongLaterAxes(const std::vector<std::uint32_t>& far, const Along& along, const Cut& cut,
                                     std::vector<detail::Window>& windows, std::vector<double>& offsets,
                                     std::size_t& queries) {
    std::vector<std::uint32_t> owner;
    const std::vector<detail::Window> later = laterAxesWindows(far, along, owner);
    queries += later.size();
    const std::vector<double> d = cut(later);
    std::vector<char> nearer(windows.size(), 0);
    for (std::size_t k = 0; k < later.size(); ++k) {
        const std::uint32_t i = owner[k];
        Vec3 point(0.0), normal(0.0);
        along(i, point, normal);
        if (std::isnan(d[k]) || !inward(normal, later[k].axis, d[k])) continue;
        if (!std::isnan(offsets[i]) && std::abs(d[k]) >= std::abs(offsets[i])) continue;
        offsets[i] = d[k];
        windows[i] = later[k];
        nearer[i] = 1;
    }
    return std::size_t(std::count(nearer.begin(), nearer.end(), char(1)));
}

/// The triangles that take part where an active triangle with a corner in `changed` passes
/// through another active triangle (detail::crossingTriangles).
std::vector<std::uint32_t> changedCrossings(const Mesh& mesh, const std::vector<std::uint32_t>& active,
                                            const std::vector<std::uint32_t>& changed) {
    std::vector<char> flag(mesh.vertices.size(), 0);
    for (std::uint32_t v : changed) flag[v] = 1;
    std::vector<std::uint32_t> touched;
    for (std::uint32_t t : active) {
        const Mesh::Triangle& tri = mesh.triangles[t];
        if (flag[tri[0]] || flag[tri[1]] || flag[tri[2]]) touched.push_back(t);
    }
    return detail::crossingTriangles(mesh, touched, active, kCrossingTolerance);
}

/// Given the vertex moves in `moved` (vertex, position before), already made, undoes those around
/// any fold of the mesh, or any triangle the moves take through another (changedCrossings), one
/// ring farther each pass, until there are none or they are not the moves' doing. `watch` follows
/// the mesh's folds (every earlier move told). A crossing's triangles have their moves undone in
/// the pass that finds it, so each pass after the first looks only at the triangles round the
/// vertices it put back. Returns the indices in `moved` of the moves undone; `back` counts them,
/// `crossed` the triangles found passing through another.
std::vector<std::uint32_t> moveUnlessFolding(Mesh& mesh, const std::vector<std::uint32_t>& active,
                                             const std::vector<std::pair<std::uint32_t, Vec3>>& moved,
                                             FoldWatch& watch, std::size_t& back, std::size_t& crossed) {
    std::vector<std::uint32_t> changed;
    for (const auto& [v, old] : moved) changed.push_back(v);
    std::vector<char> near, grown;
    for (int pass = 0; !moved.empty(); ++pass) {
        watch.moved(changed);
        std::vector<std::uint32_t> folded = watch.folded();
        const std::vector<std::uint32_t> through = changedCrossings(mesh, active, changed);
        crossed += through.size();
        folded.insert(folded.end(), through.begin(), through.end());
        if (folded.empty()) break;
        near.assign(mesh.vertices.size(), 0);
        for (std::uint32_t t : folded)
            for (std::uint32_t v : mesh.triangles[t]) near[v] = 1;
        for (int ring = 0; ring < std::min(pass, kSnapRings); ++ring) {
            grown = near;
            for (std::uint32_t t : active) {
                const Mesh::Triangle& tri = mesh.triangles[t];
                if (near[tri[0]] || near[tri[1]] || near[tri[2]]) grown[tri[0]] = grown[tri[1]] = grown[tri[2]] = 1;
            }
            near.swap(grown);
        }
        changed.clear();
        for (const auto& [v, old] : moved)
            if (near[v] && mesh.vertices[v] != old) mesh.vertices[v] = old, changed.push_back(v);
        const std::size_t undone = changed.size();
        back += undone;
        if (undone == 0 && pass >= kSnapRings) break;  // the folds are not the moves' doing
    }
    std::vector<std::uint32_t> undone;
    for (std::size_t i = 0; i < moved.size(); ++i)
        if (mesh.vertices[moved[i].first] == moved[i].second) undone.push_back(std::uint32_t(i));
    return undone;
}

/// Moves the mesh's vertices that lie off the exact part onto it: the mesher puts a vertex on a
/// sharp edge where the planes of its crossings meet, and a cusp the lattice did not see may have
/// cut that corner away. (Vertices on the lattice's crossings are exact already and stay.) Only
/// vertices some sweep comes near, whose triangles are all in `active`, are tested, along the
/// coordinate axis nearest their normals. Where the moved mesh folds, the moves around the fold
/// are undone (moveUnlessFolding). A vertex moved back, or whose window found no crossing, is tried
/// again along each axis within 75 degrees of its normal, the shortest move first, where the move
/// takes it into the material (inward): near a crest the mesher's normal can lean far from the
/// part's, and a move along another axis may reach the part without folding. Returns the number of
/// vertices moved.
std::size_t snapVertices(Mesh& mesh, const std::vector<std::uint32_t>& active, const detail::SweptCells& cells,
                         const Box& stock, const ToolPath& path, const ToolTable& tools, const RefineOptions& o,
                         RefineStats& st) {
    std::vector<Vec3> normal;
    detail::reservePopulated(normal, mesh.vertices.size());
    normal.assign(mesh.vertices.size(), Vec3(0.0));
    std::vector<double> longest;  // the longest edge at each vertex
    detail::reservePopulated(longest, mesh.vertices.size());
    longest.assign(mesh.vertices.size(), 0.0);
    for (std::uint32_t t : active) {
        const Mesh::Triangle& tri = mesh.triangles[t];
        const Vec3 a = mesh.areaVector(t);
        for (int k = 0; k < 3; ++k) {
            normal[tri[k]] += a;
            const double l = glm::length(mesh.vertices[tri[(k + 1) % 3]] - mesh.vertices[tri[k]]);
            longest[tri[k]] = std::max(longest[tri[k]], l);
            longest[tri[(k + 1) % 3]] = std::max(longest[tri[(k + 1) % 3]], l);
        }
    }
    std::vector<std::uint32_t> asked;
    for (std::uint32_t v = 0; v < mesh.vertices.size(); ++v)
        if (normal[v] != Vec3(0.0) && cells.reached(mesh.vertices[v])) asked.push_back(v);
    FoldWatch watch(mesh);
    // Along the nearest axis.
    std::vector<detail::Window> windows = windowsFor(asked, [&](std::uint32_t v, Vec3& point, Vec3& n) {
        point = mesh.vertices[v];
        n = normal[v];
    });
    st.queries += windows.size();
    std::vector<double> offsets = exactOffsets(windows, cells, stock, path, tools, o, "snap 1");
    // A crossing farther than kSlidFraction of the vertex's longest edge may lie along the part
    // rather than across it (a wall's crease vertex 0.01 mm outside a nearly vertical wall moved
    // down it by 0.1 mm along z, bear at (58.40, 26.89, -4.13)): the other axes within 75 degrees
    // of the normal are asked too, and the nearest crossing inward is kept.
    {
        std::vector<std::uint32_t> far;  // indices into asked
        for (std::size_t i = 0; i < asked.size(); ++i)
            if (std::abs(offsets[i]) > std::max(o.tolerance, kSlidFraction * longest[asked[i]]))
                far.push_back(std::uint32_t(i));
        st.laterAxis += takeNearerAlongLaterAxes(
            far,
            [&](std::uint32_t i, Vec3& point, Vec3& n) {
                point = mesh.vertices[asked[i]];
                n = normal[asked[i]];
            },
            [&](const std::vector<detail::Window>& later) {
                return exactOffsets(later, cells, stock, path, tools, o, "snap 2");
            },
            windows, offsets, st.queries);
    }
    struct Candidate {
        int axis = 0;
        double offset = 0.0;
    };
    std::vector<std::pair<std::uint32_t, Vec3>> moved;  // vertex, old position
    std::vector<Candidate> first;                       // per move, what it was
    std::vector<std::uint32_t> retry;                   // no crossing, or moved back
    for (std::size_t i = 0; i < asked.size(); ++i) {
        const std::uint32_t v = asked[i];
        if (std::isnan(offsets[i])) {
            retry.push_back(v);
        } else if (std::abs(offsets[i]) > o.tolerance) {
            moved.push_back({v, mesh.vertices[v]});
            first.push_back({windows[i].axis, offsets[i]});
            mesh.vertices[v][windows[i].axis] += offsets[i];
        }
    }
    const std::vector<std::uint32_t> back = moveUnlessFolding(mesh, active, moved, watch, st.snapRefused, st.crossed);
    std::size_t done = moved.size() - back.size();
    const std::size_t unanswered = retry.size();
    for (std::uint32_t i : back) retry.push_back(moved[i].first);

    // Along every axis within 75 degrees of the normal, the shortest move first, inward only (a
    // vertex moved back keeps its first move among them). A vertex within the tolerance on some
    // axis is on the part already and stays.
    std::vector<std::array<Candidate, 3>> candidates(retry.size());
    std::vector<int> count(retry.size(), 0);
    std::vector<char> onPart(retry.size(), 0);
    for (std::size_t b = 0; b < back.size(); ++b) {
        candidates[unanswered + b][0] = first[back[b]];
        count[unanswered + b] = 1;
    }
    if (!retry.empty()) {
        std::vector<std::uint32_t> items(retry.size());  // indices into retry
        for (std::size_t k = 0; k < retry.size(); ++k) items[k] = std::uint32_t(k);
        std::vector<std::uint32_t> owner;
        windows = laterAxesWindows(
            items,
            [&](std::uint32_t k, Vec3& point, Vec3& n) {
                point = mesh.vertices[retry[k]];
                n = normal[retry[k]];
            },
            owner);
        st.queries += windows.size();
        offsets = exactOffsets(windows, cells, stock, path, tools, o, "snap 2");
        for (std::size_t i = 0; i < windows.size(); ++i) {
            const std::uint32_t k = owner[i];
            if (std::abs(offsets[i]) <= o.tolerance) onPart[k] = 1;
            else if (!std::isnan(offsets[i]) && inward(normal[retry[k]], windows[i].axis, offsets[i]))
                candidates[k][std::size_t(count[k]++)] = {windows[i].axis, offsets[i]};
        }
        // A vertex no axis found a crossing for is asked again along the nearest, kFarReach times
        // as far (a wedge's tip past the next lattice line).
        std::vector<std::uint32_t> lost;  // indices into retry
        for (std::uint32_t k = 0; k < unanswered; ++k)
            if (count[k] == 0 && !onPart[k]) lost.push_back(k);
        windows = windowsFor(lost, [&](std::uint32_t k, Vec3& point, Vec3& n) {
            point = mesh.vertices[retry[k]];
            n = normal[retry[k]];
        });
        st.queries += windows.size();
        offsets = exactOffsets(windows, cells, stock, path, tools, o, "snap 3", kFarReach * o.window);
        for (std::size_t i = 0; i < windows.size(); ++i)
            if (!std::isnan(offsets[i]) && std::abs(offsets[i]) > o.tolerance)
                candidates[lost[i]][std::size_t(count[lost[i]]++)] = {windows[i].axis, offsets[i]};
    }
    std::vector<std::uint32_t> trying;  // indices into retry
    for (std::size_t k = 0; k < retry.size(); ++k) {
        std::stable_sort(candidates[k].begin(), candidates[k].begin() + count[k],
                         [](const Candidate& a, const Candidate& b) { return std::abs(a.offset) < std::abs(b.offset); });
        if (!onPart[k]) trying.push_back(std::uint32_t(k));
    }
    // Moves each vertex retry[k] of `ks` by `scale` times its candidate pick(k), undoes the moves
    // that fold (moveUnlessFolding) and returns the ks of those.
    const auto tryMoves = [&](const std::vector<std::uint32_t>& ks, const auto& pick, double scale) {
        moved.clear();
        for (std::uint32_t k : ks) {
            const Candidate& c = pick(k);
            moved.push_back({retry[k], mesh.vertices[retry[k]]});
            mesh.vertices[retry[k]][c.axis] += scale * c.offset;
        }
        const std::vector<std::uint32_t> undone =
            moveUnlessFolding(mesh, active, moved, watch, st.snapRefused, st.crossed);
        done += moved.size() - undone.size();
        std::vector<std::uint32_t> folded;
        for (std::uint32_t i : undone) folded.push_back(ks[i]);
        return folded;
    };
    // Each vertex's candidates in turn, the shortest first; then, where every one folded, part of
    // the shortest (kPartialMove).
    std::vector<std::uint32_t> exhausted;  // indices into retry: every candidate folded
    for (int attempt = 0; attempt < 3 && !trying.empty(); ++attempt) {
        std::vector<std::uint32_t> ks;
        for (std::uint32_t k : trying) {
            if (attempt < count[k]) ks.push_back(k);
            else if (count[k] > 0) exhausted.push_back(k);
        }
        trying = tryMoves(ks, [&](std::uint32_t k) { return candidates[k][std::size_t(attempt)]; }, 1.0);
    }
    exhausted.insert(exhausted.end(), trying.begin(), trying.end());
    double scale = 1.0;
    for (int t = 0; t < kPartialTries && !exhausted.empty(); ++t) {
        scale *= kPartialMove;
        const std::size_t tried = exhausted.size();
        exhausted = tryMoves(exhausted, [&](std::uint32_t k) { return candidates[k][0]; }, scale);
        st.snapPartial += tried - exhausted.size();
    }
    st.snapped += done;
    return done;
}

/// One round of refinement on the active triangles of a mesh (local indices i into `active`).
class Round {
public:
    Round(Mesh& mesh, std::vector<std::uint32_t> active, const RefineOptions& o)
        : mesh_(mesh), active_(std::move(active)), edges_(detail::buildEdges(mesh, active_)), o_(o) {}

    /// Tests the edges whose upper vertex is at least `firstNew` (all edges: 0), and splits those
    /// off the exact part. Returns the number of edges split; `check` receives the mesh's check.
    std::size_t run(std::size_t firstNew, const detail::SweptCells& cells, const Box& stock, const ToolPath& path,
                    const ToolTable& tools, RefineStats& stats, MeshCheck& check) {
        propose(firstNew, cells, stock, path, tools, stats);
        std::vector<std::uint32_t> work;
        for (std::uint32_t i = 0; i < active_.size(); ++i)
            if (mask(i)) work.push_back(i);
        settle(work, stats);
        // Whether a triangle folds against its vertices' normals depends on the stars around its
        // corners, which the pieces' test cannot see. Where the split mesh folds, the splits of the
        // folded piece's parent are refused first; where it folds again, or a triangle this round
        // did not split folds, every split of the triangles around the parent's (the triangle's)
        // corners is refused: those stars are then the unsplit mesh's, which did not fold.
        // Refusals only grow, so this ends. (Refusing the corners' splits at once had refused, on
        // bear at (50.43, 22.55, -5.27), a split 0.087 mm into a ridge that a neighbour's sliver
        // folded, and left a face 0.28 h inside the part.)
        std::vector<std::uint32_t> folded;
        std::vector<char> blamed(active_.size(), 0);  // parents whose own splits a fold refused
        std::size_t added = 0;
        for (;;) {
            added = apply();
            check = checkMesh(mesh_, &folded);
            const std::vector<std::uint32_t> crossed = crossings();
            stats.crossed += crossed.size();
            folded.insert(folded.end(), crossed.begin(), crossed.end());
            if (folded.empty() || added == 0) break;
            std::size_t refused = 0;
            const auto refuse = [&](std::uint32_t e) {
                split_[e] = 0;
                ++refused;
                // The triangles across the edge lose a split too: their pieces are tested again.
                for (std::uint32_t other : edges_.triangles[e]) work.push_back(other);
            };
            std::vector<char> corner(mesh_.vertices.size(), 0);
            for (std::uint32_t t : folded) {
                const std::uint32_t parent = parentOf(t);
                if (parent != kNoTriangle && !blamed[parent]) {
                    blamed[parent] = 1;
                    const std::size_t before = refused;
                    for (int k = 0; k < 3; ++k)
                        if (split_[edges_.edgeOf[3 * parent + k]]) refuse(edges_.edgeOf[3 * parent + k]);
                    if (refused > before) continue;
                }
                for (std::uint32_t v : parent == kNoTriangle ? mesh_.triangles[t] : oldTriangle(parent)) corner[v] = 1;
            }
            for (std::uint32_t i = 0; i < active_.size(); ++i) {
                const Mesh::Triangle& tri = oldTriangle(i);
                if (!corner[tri[0]] && !corner[tri[1]] && !corner[tri[2]]) continue;
                for (int k = 0; k < 3; ++k)
                    if (split_[edges_.edgeOf[3 * i + k]]) refuse(edges_.edgeOf[3 * i + k]);
            }
            stats.refused += refused;
            if (refused == 0) break;  // nothing of this round's making folds: keep it as it is
            undo();
            settle(work, stats);
        }
        stats.split += added;
        return added;
    }

private:
    /// Windows on the candidate edges' midpoints, and the splits they propose.
    void propose(std::size_t firstNew, const detail::SweptCells& cells, const Box& stock, const ToolPath& path,
                 const ToolTable& tools, RefineStats& stats) {
        const std::size_t nEdges = edges_.ends.size();
        detail::reservePopulated(split_, nEdges);
        detail::reservePopulated(at_, nEdges);
        detail::reservePopulated(moved_, nEdges);
        split_.assign(nEdges, 0);
        at_.resize(nEdges);
        moved_.assign(nEdges, 0.0);
        // One window per candidate edge, along the axis nearest its two triangles' mean normal.
        std::vector<std::uint32_t> asked;
        for (std::size_t e = 0; e < nEdges; ++e)
            if (edges_.ends[e][1] >= firstNew && edges_.triangles[e][0] != kNoTriangle) asked.push_back(std::uint32_t(e));
        // Two triangles facing apart (a fin) give no direction: left alone.
        std::vector<detail::Window> windows = windowsFor(asked, [&](std::uint32_t e, Vec3& point, Vec3& n) {
            n = edgeNormal(e);
            point = 0.5 * (mesh_.vertices[edges_.ends[e][0]] + mesh_.vertices[edges_.ends[e][1]]);
        });
        stats.queries += windows.size();
        const auto cut = [&](const std::vector<detail::Window>& w) {
            return exactOffsets(w, cells, stock, path, tools, o_, "refine " + std::to_string(stats.rounds));
        };
        std::vector<double> offsets = cut(windows);
        // Midpoints whose crossing lies far along the nearest axis, or that found none, are asked
        // along the other axes too (kSlidFraction). On a wall's rounded top, the edge along the
        // crease has the wall's and the top's normals: its window ran along y and met the top
        // 0.12 mm from the corner, and the pieces cut the corner off by 0.23 h (bear,
        // `--refine 1`, at (23.13, 26.84, -4.12)); along z the corner lies 0.017 mm below.
        std::vector<std::uint32_t> again;  // indices into asked
        for (std::size_t i = 0; i < asked.size(); ++i)
            if (std::isnan(offsets[i]) || std::abs(offsets[i]) > kSlidFraction * edgeLength(asked[i]))
                again.push_back(std::uint32_t(i));
        stats.laterAxis += takeNearerAlongLaterAxes(
            again,
            [&](std::uint32_t i, Vec3& point, Vec3& n) {
                point = windows[i].point;
                n = edgeNormal(asked[i]);
            },
            cut, windows, offsets, stats.queries);

        for (std::size_t i = 0; i < asked.size(); ++i) {
            const double d = offsets[i];
            if (std::isnan(d)) {
                ++stats.noCrossing;
                continue;
            }
            if (std::abs(d) <= o_.tolerance) continue;
            const std::uint32_t e = asked[i];
            Vec3 q = windows[i].point;
            q[windows[i].axis] += d;
            split_[e] = 1;
            at_[e] = q;
            moved_[e] = std::abs(d) / edgeLength(e);
        }
    }

    /// The triangles that take part where a piece of this round passes through another of the
    /// round's triangles (detail::crossingTriangles): the split mesh, unlike the mesher's, may
    /// tuck a piece through a neighbour without folding against its vertices' normals (heart,
    /// `--refine 1`: 779 such pairs before this test, the mesher's own mesh 7).
    /// Only the triangles whose splits changed since the last call are looked at: the first
    /// time every split triangle's pieces, later those of triangles split anew, and triangles whose
    /// splits were all refused (the triangles of a crossing found before have their splits
    /// refused, so what stays unchanged crossed nothing).
    std::vector<std::uint32_t> crossings() {
        lastMask_.resize(active_.size(), 0);
        std::vector<char> changed(active_.size(), 0);
        std::vector<std::uint32_t> pieces, partners(active_);
        for (std::uint32_t i = 0; i < active_.size(); ++i) {
            const unsigned m = mask(i);
            changed[i] = m != lastMask_[i];
            lastMask_[i] = m;
            if (changed[i]) pieces.push_back(active_[i]);
        }
        for (std::size_t t = oldTriangles_; t < mesh_.triangles.size(); ++t) {
            partners.push_back(std::uint32_t(t));
            if (changed[appendedParent_[t - oldTriangles_]]) pieces.push_back(std::uint32_t(t));
        }
        return detail::crossingTriangles(mesh_, pieces, partners, kCrossingTolerance);
    }

    double edgeLength(std::uint32_t e) const {
        return glm::length(mesh_.vertices[edges_.ends[e][1]] - mesh_.vertices[edges_.ends[e][0]]);
    }

    /// How far edge e's midpoint lies off the part, where it is split (mm).
    double offsetOf(std::uint32_t e) const { return moved_[e] * edgeLength(e); }

    /// The sum of the unit normals of edge e's two triangles.
    Vec3 edgeNormal(std::uint32_t e) const {
        return unit(mesh_.areaVector(active_[edges_.triangles[e][0]])) +
               unit(mesh_.areaVector(active_[edges_.triangles[e][1]]));
    }

    unsigned mask(std::uint32_t i) const {
        unsigned bits = 0;
        for (int k = 0; k < 3; ++k)
            if (split_[edges_.edgeOf[3 * i + k]]) bits |= 1u << k;
        return bits;
    }

    /// The pieces of local triangle i under the current splits, with their vertex ids (new
    /// vertices as numbered by newVertex_); the count, 0 for none or a bad split.
    int pieces(std::uint32_t i, std::array<Local, 4>& out, std::array<std::uint32_t, 6>& ids) const {
        const Mesh::Triangle& tri = oldTriangle(i);
        unsigned bits = 0;
        std::array<Vec3, 6> p;
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t e = edges_.edgeOf[3 * i + k];
            ids[k] = tri[k];
            ids[3 + k] = newVertex_.empty() ? 0 : newVertex_[e];
            p[k] = mesh_.vertices[tri[k]];
            p[3 + k] = split_[e] ? at_[e] : Vec3(0.0);
            if (split_[e]) bits |= 1u << k;
        }
        if (!bits) return 0;
        const Vec3 n = unit(glm::cross(p[1] - p[0], p[2] - p[0]));
        return detail::splitPieces(p, bits, n, out);
    }

    /// Refuses splits until every split triangle's pieces are good, and looks again at the other
    /// triangle of each edge refused. A bad triangle gives up the split that lies least off the
    /// part among those whose refusal alone makes its pieces good; where none does, its most
    /// displaced split. (The bull-undercut study at h = 0.5, `--refine 1`, at (45.56, 40.00, 15.25):
    /// a triangle with a corner on a cusp's ridge cut under it by 0.070 mm with its far edge. With
    /// that edge split on the ridge and the two along the flanks 0.004 mm off, the middle piece
    /// turned 87 degrees from the triangle; giving up the ridge's split, the most displaced, left
    /// the edge under the ridge, where giving up a flank's lets the pieces follow the ridge.)
    void settle(std::vector<std::uint32_t>& work, RefineStats& stats) {
        std::array<Local, 4> out;
        std::array<std::uint32_t, 6> ids;
        while (!work.empty()) {
            const std::uint32_t i = work.back();
            work.pop_back();
            if (!mask(i) || pieces(i, out, ids) > 0) continue;
            std::uint32_t mostDisplaced = kNoTriangle, cheapest = kNoTriangle;
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t e = edges_.edgeOf[3 * i + k];
                if (!split_[e]) continue;
                if (mostDisplaced == kNoTriangle || moved_[e] > moved_[mostDisplaced]) mostDisplaced = e;
                split_[e] = 0;
                const bool mends = !mask(i) || pieces(i, out, ids) > 0;
                split_[e] = 1;
                if (mends && (cheapest == kNoTriangle || offsetOf(e) < offsetOf(cheapest))) cheapest = e;
            }
            const std::uint32_t given = cheapest != kNoTriangle ? cheapest : mostDisplaced;
            split_[given] = 0;
            ++stats.refused;
            work.push_back(i);
            for (std::uint32_t other : edges_.triangles[given])
                if (other != i) work.push_back(other);
        }
    }

    /// The triangle local i was before apply().
    const Mesh::Triangle& oldTriangle(std::uint32_t i) const {
        return applied_ && slotOf_[i] != kNoTriangle ? replaced_[slotOf_[i]] : mesh_.triangles[active_[i]];
    }

    /// The local triangle a triangle of the split mesh comes from (kNoTriangle: not this round's).
    std::uint32_t parentOf(std::uint32_t t) const {
        if (t >= oldTriangles_) return appendedParent_[t - oldTriangles_];
        const auto it = std::lower_bound(splitGlobal_.begin(), splitGlobal_.end(), t);
        return it != splitGlobal_.end() && *it == t ? splitLocal_[std::size_t(it - splitGlobal_.begin())] : kNoTriangle;
    }

    /// Splits the mesh in place: new vertices appended in edge order, each split triangle replaced
    /// by its first piece and the others appended in triangle order. Returns the edges split.
    std::size_t apply() {
        oldVertices_ = mesh_.vertices.size();
        oldTriangles_ = mesh_.triangles.size();
        newVertex_.assign(split_.size(), 0);
        detail::reservePopulated(mesh_.vertices,
                                 oldVertices_ + std::size_t(std::count(split_.begin(), split_.end(), char(1))));
        std::size_t added = 0;
        for (std::size_t e = 0; e < split_.size(); ++e) {
            if (!split_[e]) continue;
            newVertex_[e] = std::uint32_t(mesh_.vertices.size());
            mesh_.vertices.push_back(at_[e]);
            ++added;
        }
        // The split triangles, in order, with their pieces counted (in parallel), then written.
        splitLocal_.clear();
        for (std::uint32_t i = 0; i < active_.size(); ++i)
            if (mask(i)) splitLocal_.push_back(i);
        const std::size_t n = splitLocal_.size();
        std::vector<std::uint32_t> extra(n + 1, 0);
        tbb::parallel_for(std::size_t(0), n, [&](std::size_t j) {
            std::array<Local, 4> out;
            std::array<std::uint32_t, 6> ids;
            extra[j + 1] = std::uint32_t(std::max(0, pieces(splitLocal_[j], out, ids) - 1));
        });
        for (std::size_t j = 0; j < n; ++j) extra[j + 1] += extra[j];
        replaced_.resize(n);
        splitGlobal_.resize(n);
        slotOf_.assign(active_.size(), kNoTriangle);
        for (std::size_t j = 0; j < n; ++j) {
            slotOf_[splitLocal_[j]] = std::uint32_t(j);
            splitGlobal_[j] = active_[splitLocal_[j]];
            replaced_[j] = mesh_.triangles[splitGlobal_[j]];
        }
        detail::reservePopulated(mesh_.triangles, oldTriangles_ + extra[n]);
        mesh_.triangles.resize(oldTriangles_ + extra[n]);
        appendedParent_.resize(extra[n]);
        applied_ = true;
        tbb::parallel_for(std::size_t(0), n, [&](std::size_t j) {
            std::array<Local, 4> out;
            std::array<std::uint32_t, 6> ids;
            const int count = pieces(splitLocal_[j], out, ids);
            const auto piece = [&](const Local& l) { return Mesh::Triangle{ids[l[0]], ids[l[1]], ids[l[2]]}; };
            mesh_.triangles[splitGlobal_[j]] = piece(out[0]);
            for (int k = 1; k < count; ++k) {
                mesh_.triangles[oldTriangles_ + extra[j] + k - 1] = piece(out[k]);
                appendedParent_[extra[j] + k - 1] = splitLocal_[j];
            }
        });
        return added;
    }

    /// Puts the mesh back as it was before apply().
    void undo() {
        for (std::size_t j = 0; j < splitGlobal_.size(); ++j) mesh_.triangles[splitGlobal_[j]] = replaced_[j];
        mesh_.triangles.resize(oldTriangles_);
        mesh_.vertices.resize(oldVertices_);
        applied_ = false;
    }

    Mesh& mesh_;
    std::vector<std::uint32_t> active_;  ///< local triangle -> mesh triangle
    EdgeTable edges_;
    const RefineOptions& o_;
    // Per edge: whether it is split, where, and how far that is from its midpoint per length.
    std::vector<char> split_;
    std::vector<Vec3> at_;
    std::vector<double> moved_;
    // What apply() did, for undo() and parentOf().
    bool applied_ = false;
    std::size_t oldVertices_ = 0, oldTriangles_ = 0;
    std::vector<std::uint32_t> newVertex_;      ///< per edge
    std::vector<std::uint32_t> splitLocal_;     ///< split local triangles, in order
    std::vector<std::uint32_t> splitGlobal_;    ///< their mesh indices (increasing)
    std::vector<std::uint32_t> slotOf_;         ///< local triangle -> index in splitLocal_, or kNoTriangle
    std::vector<Mesh::Triangle> replaced_;      ///< their triangles before apply()
    std::vector<std::uint32_t> appendedParent_; ///< per appended triangle, its local parent
    std::vector<unsigned> lastMask_;            ///< per local triangle, its splits at crossings()
};

}  // namespace

void refineMesh(Mesh& mesh, const Box& stock, const ToolPath& path, const ToolTable& tools,
                const RefineOptions& options, RefineStats* stats) {
    RefineStats local;
    RefineStats& st = stats ? *stats : local;
    std::size_t firstNew = 0;
    bool checked = false;
    if (options.rounds > 0 && !mesh.empty() &&
        !(options.memoryBytes > 0.0 && kRoundBytesPerTriangle * double(mesh.triangles.size()) > options.memoryBytes)) {
        const detail::SweptCells cells(stock, path, tools, 8.0 * options.window, options.window);
        snapVertices(mesh, activeTriangles(mesh, cells), cells, stock, path, tools, options, st);
    }
    for (int round = 0; round < options.rounds && !mesh.empty(); ++round) {
        const double need = kRoundBytesPerTriangle * double(mesh.triangles.size());
        if (options.memoryBytes > 0.0 && need > options.memoryBytes) {
            st.roundNeeded = need;
            break;
        }
        // Cells of a few windows' lengths, fine enough to leave the block's untouched faces out.
        const detail::SweptCells cells(stock, path, tools, 8.0 * options.window,
                                       options.window + longestEdge(mesh));
        Round r(mesh, activeTriangles(mesh, cells), options);
        // The first round tests every edge; later rounds only the edges the last one made (the
        // others were within the tolerance, or refused).
        const std::size_t before = mesh.vertices.size();
        checked = true;
        ++st.rounds;
        if (r.run(firstNew, cells, stock, path, tools, st, st.check) == 0) break;
        firstNew = before;
    }
    if (st.rounds > 0) {
        st.collapsed = collapseShortEdges(mesh, kShortEdge * options.window);
        checked = st.collapsed == 0;
    }
    if (!checked) st.check = checkMesh(mesh);
}

}  // namespace dexelmill
