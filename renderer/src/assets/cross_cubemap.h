// LDR horizontal-cross cube maps (the BRDFA Engine's skyboxes) and their conversion to the
// internal cube map (environment_maps.h).
//
// Layout: an image 4N wide and 3N high holding six N x N faces, labelled as usual:
//   row 0: [  _ , +Y ,  _ ,  _ ]
//   row 1: [ -X , +Z , +X , -Z ]
//   row 2: [  _ , -Y ,  _ ,  _ ]
// Orientation: the cross is a picture of the surroundings seen from inside. Folded into a cube
// with the pictures facing inwards, a viewer at its centre sees every face unmirrored, upright
// on the middle row, the middle row as one panorama (turning right goes left to right), +Y
// above +Z with its bottom edge on +Z's top edge and -Y below +Z with its top edge on +Z's
// bottom edge. The labels are those of the usual (left-handed, DirectX/GL cube face) naming:
// looking at +Z with +Y up, +X is on the right. Our world is right-handed with the default
// camera looking down -Z, so the label's z is flipped: the cross's front face "+Z" is our -Z
// (what the default camera sees, like an equirect's centre), "+X" is our +X (the camera's
// right), "-Z" is our +Z (behind the camera), "+Y"/"-Y" are up and down.
//   Cross pixel (column c, row r) of face F in [0, N) shows the direction
//   centre_F + s right_F + t down_F, s = (2c + 1) / N - 1, t = (2r + 1) / N - 1, with
//     "+Z": centre -Z, right +X, down -Y       "-Z": centre +Z, right -X, down -Y
//     "+X": centre +X, right +Z, down -Y       "-X": centre -X, right -Z, down -Y
//     "+Y": centre +Y, right +X, down -Z       "-Y": centre -Y, right +X, down +Z
#pragma once

#include <cstdint>
#include <string>

#include "assets/environment_maps.h"

namespace brdfa {

// InvalidArgument unless width = 4 N and height = 3 N for some N >= 1.
Result<void> checkCrossSize(int width, int height);

// Converts an sRGB RGBA8 cross (row 0 at the top; alpha ignored) to the internal cube, in
// linear radiance. Faces keep their size (an exact texel copy) up to 1024; larger ones are
// box-filtered down to 1024.
EnvironmentData crossToCube(const uint8_t* rgba, int width, int height, const std::string& name);

}  // namespace brdfa
