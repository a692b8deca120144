// Constants the shared terms use. Named with the renderer's `brdfa_` prefix so that a BRDF file
// that includes terms can still declare its own `PI` (as every built-in does).
const float brdfa_PI = 3.14159265358979323846;
