// Globals a BRDF file may read besides its parameters (docs/design.md section 3). Set by the
// integrator before each BRDF() call.
vec2 texCoord;  // the surface's texture coordinate at the shaded pixel

#if defined(BRDFA_TEXTURES)
// The object's textures (docs/design.md section 3). A slot the scene leaves unbound holds a 1x1
// white texture, so a BRDF that multiplies by it renders as if untextured. Declared only when
// the BRDF names one (brdf_features.cpp).
layout(set = 1, binding = 2) uniform sampler2D iTexture0;
layout(set = 1, binding = 3) uniform sampler2D iTexture1;
layout(set = 1, binding = 4) uniform sampler2D iTexture2;
layout(set = 1, binding = 5) uniform sampler2D iTexture3;
#endif
