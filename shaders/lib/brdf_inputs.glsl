// Globals a BRDF file may read besides its parameters (DESIGN.md section 3). Set by the
// integrator before each BRDF() call.
vec2 texCoord;  // the surface's texture coordinate at the shaded pixel
