// Visibility pass: writes what shading needs per pixel (see shaders/lib/bindings.glsl).
layout(location = 0) in vec3 inWorldPos;
layout(location = 1) in vec3 inNormal;
layout(location = 2) in vec2 inTexCoord;
layout(location = 3) in vec4 inTangent;

layout(set = 1, binding = 1) uniform BrdfaObject {
  mat4 model;
  mat4 normalMatrix;
  vec4 id;
} brdfa_object;

layout(location = 0) out vec4 outPosition;
layout(location = 1) out vec4 outNormal;
layout(location = 2) out vec4 outTangent;

void main() {
  // Surfaces are two-sided: a back face is shaded with its normal turned to the viewer.
  vec3 n = normalize(inNormal) * (gl_FrontFacing ? 1.0 : -1.0);
  float handedness = inTangent.w < 0.0 ? -1.0 : 1.0;
  outPosition = vec4(inWorldPos, brdfa_object.id.x * handedness);
  outNormal = vec4(n, inTexCoord.x);
  outTangent = vec4(inTangent.xyz, inTexCoord.y);
}
