// Newell's teapot: 32 bicubic Bezier patches over 306 control points.
//
// Modelled by Martin Newell at the University of Utah in 1975; the data set as distributed in
// F. C. Crow, "The Origins of the Teapot", IEEE Computer Graphics and Applications 7(1), 8-19,
// 1987 (rim, body, handle, spout, lid and the bottom that later versions added). Public data.
//
// Original units and frame: z up, the bottom at z = 0, the body's rim radius 1.5 at z = 2.4,
// the top of the lid knob at z = 3.15, the spout toward +x (tip near x = 3.4), the handle toward
// -x (reaching x = -3.0). meshes.cpp turns it into this project's +Y-up frame.
#pragma once

#include <cstdint>

namespace brdfa::teapot {

inline constexpr int kPatchCount = 32;
inline constexpr int kControlPointCount = 306;

// Patch p's control point (row r, column c), r, c in 0..3, is
// kControlPoints[kPatches[p][4 * r + c] - 1]: the table keeps the original 1-based numbering.
// Seen from outside, cross(dP/dc, dP/dr) points outward on every patch (columns run along u,
// rows along v); the knob top and the bottom centre are poles where a whole row is one point.
extern const uint16_t kPatches[kPatchCount][16];
extern const float kControlPoints[kControlPointCount][3];

// Table order: 0..3 rim, 4..11 body, 12..15 handle, 16..19 spout, 20..27 lid, 28..31 bottom.
// Handle and spout patches come in rings of two around their tube (one for y < 0, one for
// y > 0); every other part in rings of four around the z axis.
inline constexpr int kFirstTubePatch = 12;
inline constexpr int kEndTubePatch = 20;

}  // namespace brdfa::teapot
