// The levels of the turning sweep's searches (TurningSweep::intersect, turning.cpp), shared by
// its files: the static search's deepest level, the linear nodes' (notes c and h), and the heap
// index that names a linear node.
#pragma once

#include <cstdint>

namespace dexelmill::turning {

/// The deepest level of the search: a node of width 2^-kMaxLevel. Reached only when
/// speed / 2^(kMaxLevel + 1) is still above epsilon, i.e. a tool point travelling 1e14 epsilon.
constexpr int kMaxLevel = 60;

/// The deepest level of the linear-node search (note h). A move that would need deeper ones is
/// searched by static poses. Near a graze the search stops about where note j's bound meets the
/// tolerance, far above the leaves at a fine tolerance: a flat D10 fed 80 mm while it turns 30
/// degrees (h = 0.2 mm, one thread, whole process) took 1.29 s at 1e-6 mm with leaves down to
/// level 23, against 43 s by static poses under a limit of 20 (0.80 s and 1.24 s at 1e-4 mm). A
/// node's heap index keeps a level of 30 within 32 bits.
constexpr int kMaxLinearLevel = 30;

/// The level of the node with heap index `heap` (the root 1, node i's halves 2i and 2i + 1): the
/// place of its highest set bit.
inline int heapLevel(std::uint32_t heap) { return 31 - __builtin_clz(heap); }

/// The width in u of the node with heap index `heap`, 2^-level, exactly: a division, where the
/// search's call of std::ldexp cost 0.8 % of boat-xyzac's cut.
inline double heapWidth(std::uint32_t heap) { return 1.0 / double(std::uint32_t(1) << heapLevel(heap)); }

}  // namespace dexelmill::turning
