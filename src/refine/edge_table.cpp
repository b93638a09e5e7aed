#include "refine/detail/edge_table.h"

#include <algorithm>

#include <tbb/parallel_for.h>

#include "memory/pages.h"

namespace dexelmill::detail {

// The slots are grouped by their first vertex (a counting sort): an edge's owner is its slot
// going up in vertex index, or its only slot, and its twin the slot going back.
EdgeTable buildEdges(const Mesh& mesh, const std::vector<std::uint32_t>& triangles) {
    const std::size_t slots = 3 * triangles.size();
    const auto from = [&](std::size_t s) { return mesh.triangles[triangles[s / 3]][s % 3]; };
    const auto to = [&](std::size_t s) { return mesh.triangles[triangles[s / 3]][(s % 3 + 1) % 3]; };
    std::vector<std::uint32_t> start(mesh.vertices.size() + 1, 0), bySource;
    reservePopulated(bySource, slots);
    bySource.resize(slots);
    for (std::size_t s = 0; s < slots; ++s) ++start[from(s) + 1];
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v) start[v + 1] += start[v];
    {
        std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
        for (std::size_t s = 0; s < slots; ++s) bySource[fill[from(s)]++] = std::uint32_t(s);
    }
    // Per slot: its twin (kNoTriangle if none or several) and whether the edge has other slots.
    std::vector<std::uint32_t> twin;
    reservePopulated(twin, slots);
    twin.assign(slots, kNoTriangle);
    std::vector<char> shared(slots, 0);
    tbb::parallel_for(std::size_t(0), slots, [&](std::size_t s) {
        const std::uint32_t a = from(s), b = to(s);
        if (a == b) return void(shared[s] = 1);  // a corner repeated: no edge to split
        std::size_t back = 0;
        for (std::uint32_t i = start[b]; i < start[b + 1]; ++i)
            if (to(bySource[i]) == a) twin[s] = bySource[i], ++back;
        for (std::uint32_t i = start[a]; i < start[a + 1]; ++i)
            if (bySource[i] != s && to(bySource[i]) == b) shared[s] = 1;
        if (back != 1) twin[s] = kNoTriangle, shared[s] = 1;
    });
    // Owners number the edges in slot order; the others take their twin's number.
    EdgeTable e;
    reservePopulated(e.edgeOf, slots);
    e.edgeOf.resize(slots);
    const auto owner = [&](std::size_t s) { return from(s) < to(s) || twin[s] == kNoTriangle; };
    std::uint32_t edges = 0;
    for (std::size_t s = 0; s < slots; ++s)
        if (owner(s)) e.edgeOf[s] = edges++;
    reservePopulated(e.ends, edges);
    reservePopulated(e.triangles, edges);
    e.ends.resize(edges);
    e.triangles.resize(edges);
    tbb::parallel_for(std::size_t(0), slots, [&](std::size_t s) {
        if (!owner(s)) {
            e.edgeOf[s] = e.edgeOf[twin[s]];
            return;
        }
        const std::uint32_t id = e.edgeOf[s];
        e.ends[id] = {std::min(from(s), to(s)), std::max(from(s), to(s))};
        e.triangles[id] = shared[s] ? std::array<std::uint32_t, 2>{kNoTriangle, kNoTriangle}
                                    : std::array<std::uint32_t, 2>{std::uint32_t(s / 3), twin[s] / 3};
    });
    return e;
}

}  // namespace dexelmill::detail
