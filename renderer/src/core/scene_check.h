// Validation of a Scene before any device work: every error names the offending field.
#pragma once

#include "brdfa/result.h"
#include "brdfa/scene.h"

namespace brdfa {

// Checks ranges and finiteness (sizes, samples, camera, transforms, parameter names and values)
// against the limits in scene.h. Names of meshes and environments are checked by the caller.
Result<void> checkScene(const Scene& scene);

}  // namespace brdfa
