// Per-vertex shading frames for meshes that do not bring their own: smooth normals from the
// triangles, tangents from the texture coordinates, and a deterministic fallback frame where the
// texture coordinates cannot give one. The results follow the conventions in meshes.h.
#pragma once

#include <glm/vec3.hpp>

#include "assets/meshes.h"

namespace brdfa {

// Sets every vertex normal to the unit, angle-weighted average of the normals of the triangles
// around the vertex's position (G. Thürmer, C. A. Wüthrich, "Computing Vertex Normals from
// Polygonal Meshes", JGT 3(1), 1998). Vertices that share a position bit for bit share the
// normal, so a mesh split along texture seams stays smooth across them. Zero-area triangles add
// nothing; a vertex with no usable triangle (or whose neighbours cancel out) gets +Y.
// Winding decides the direction: counter-clockwise triangles give outward normals.
void generateSmoothNormals(MeshData& mesh);

// Sets every vertex tangent (xyz unit and orthogonal to the vertex normal, w = +-1) from the
// texture coordinates when `hasTexCoords`: each triangle's dP/du and dP/dv (E. Lengyel,
// "Computing Tangent Space Basis Vectors for an Arbitrary Mesh", 2001), angle-weighted and
// summed per vertex, then Gram-Schmidt against the normal; w = +1 when dP/dv lies on the side of
// cross(N, T), else -1. Where that gives no direction (no texture coordinates, only zero-area
// UV triangles around the vertex, a tangent parallel to the normal), the vertex gets
// orthonormalBasis(N)'s first vector and w = +1. Needs unit normals (generateSmoothNormals).
void generateTangents(MeshData& mesh, bool hasTexCoords);

// A right-handed orthonormal basis (t, b, n) from the unit vector n: cross(n, t) = b. Branchless
// construction of T. Duff et al., "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017,
// the same as brdfa_basisFromNormal in shaders/lib/frame.glsl, so a mesh's fallback tangent and
// the shader's agree. Deterministic; note it jumps where n.z changes sign (unless n.x = 0), so
// it is a fallback, not a field meant to look smooth.
void orthonormalBasis(const glm::vec3& n, glm::vec3& t, glm::vec3& b);

}  // namespace brdfa
