#pragma once
// Usage:
//   paco::SurfaceMesh part = paco::data::generatePart(42);          // closed, outward, plane-only
//   paco::data::PartKind kind = paco::data::partKindOf(42);         // what seed 42 makes
//   paco::io::saveMesh("part.off", part);
#include <paco/common/surface_mesh.h>

#include <cstdint>
#include <string>

namespace paco::data {

/// Families of procedural CAD-like parts.
enum class PartKind {
  FeaturedBox,  ///< a stock box with pockets, steps, slots, chamfers and polygonal through-holes
  Prism,        ///< a convex polygon extruded, optionally with a through-hole
  LExtrusion,   ///< L-section extrusion
  TExtrusion,   ///< T-section extrusion
  UExtrusion,   ///< U-section extrusion
  BoxUnion,     ///< union of 2-4 overlapping boxes
};
std::string toString(PartKind kind);
/// The family seed `seed` generates (a pure function of the seed).
PartKind partKindOf(std::uint64_t seed);

/// A closed, manifold, outward-oriented triangle mesh of a plane-only part, within about
/// [-2, 2]^3, built with exact Boolean operations (CGAL Nef polyhedra). Deterministic: the same
/// seed gives the same mesh on every run. `kind` forces a family (default: partKindOf(seed)).
SurfaceMesh generatePart(std::uint64_t seed);
SurfaceMesh generatePart(std::uint64_t seed, PartKind kind);

/// The name procedural part `index` gets in a dataset: "proc-000042".
std::string proceduralPartName(std::size_t index);

}  // namespace paco::data
