#pragma once
// How much of the primitives' points a surface passes near. PolyFit's optimum can give up a
// large share of them for coverage and complexity (a building seen from above, whose walls it
// drops, keeping a slab of roof); the assembler compares it with its warm start by this.
#include <paco/assembly/polygonal_assembler.h>

#include <vector>

namespace paco::detail {

/// The share (0..1) of all points of `primitives` farther than `distance` from the surface of
/// `mesh` (in the same frame). 1 for an empty mesh; 0 when there are no points.
double shareOfPointsFartherThan(const SurfaceMesh& mesh, const std::vector<PlanarPrimitive>& primitives,
                                double distance);

}  // namespace paco::detail
