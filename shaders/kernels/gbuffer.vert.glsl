// Visibility pass: transforms one object's mesh into world and clip space.
layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec3 inNormal;
layout(location = 2) in vec2 inTexCoord;
layout(location = 3) in vec4 inTangent;  // xyz tangent, w handedness (+1 | -1)

layout(set = 1, binding = 1) uniform BrdfaObject {
  mat4 model;
  mat4 normalMatrix;  // inverse transpose of the model matrix (non-uniform scale)
  vec4 id;            // x = object id, 1-based
} brdfa_object;

layout(push_constant) uniform BrdfaRasterPush { mat4 viewProj; } brdfa_raster;

layout(location = 1) out vec3 outNormal;
layout(location = 2) out vec2 outTexCoord;
layout(location = 3) out vec4 outTangent;

void main() {
  vec4 world = brdfa_object.model * vec4(inPosition, 1.0);
  outNormal = mat3(brdfa_object.normalMatrix) * inNormal;
  outTangent = vec4(mat3(brdfa_object.model) * inTangent.xyz, inTangent.w);
  outTexCoord = inTexCoord;
  gl_Position = brdfa_raster.viewProj * world;
}
