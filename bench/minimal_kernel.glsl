// The reference for throughput: the least a GPU program can do to shade the benchmark scene
// (a GGX sphere lit by the sky cubemap, cosine-weighted samples) with no G-buffer, no
// accumulator halves, no NaN checks and no parameter block. Ray-sphere intersection replaces
// rasterization. The renderer's figure is quoted as a ratio to this kernel's, measured in the
// same run.
#version 450
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, set = 0, binding = 0) buffer Accum { vec4 accum[]; };
layout(set = 0, binding = 1) uniform samplerCube envMap;
layout(push_constant) uniform Push { uint width, height, firstSample, count; float tanHalfFov; } pc;

const float PI = 3.14159265358979323846;

uint pcg(inout uint s) {
  s = s * 747796405u + 2891336453u;
  uint w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
  return (w >> 22u) ^ w;
}
float rnd(inout uint s) { return float(pcg(s) >> 8) * (1.0 / 16777216.0); }

vec3 ggx(vec3 L, vec3 V, vec3 N) {
  const float a = 0.3;
  const vec3 f0 = vec3(0.95, 0.64, 0.54);
  float NoL = dot(N, L), NoV = dot(N, V);
  if (NoL <= 0.0 || NoV <= 0.0) return vec3(0.0);
  vec3 H = normalize(L + V);
  float NoH = clamp(dot(N, H), 0.0, 1.0), VoH = clamp(dot(V, H), 0.0, 1.0);
  float a2 = a * a;
  float d = NoH * NoH * (a2 - 1.0) + 1.0;
  float D = a2 / (PI * d * d);
  float vis = 0.5 / max(NoL * sqrt(NoV * NoV * (1.0 - a2) + a2) + NoV * sqrt(NoL * NoL * (1.0 - a2) + a2), 1e-20);
  float m = clamp(1.0 - VoH, 0.0, 1.0);
  vec3 F = f0 + (1.0 - f0) * (m * m * m * m * m);
  return D * vis * F;
}

void main() {
  uvec2 p = gl_GlobalInvocationID.xy;
  if (p.x >= pc.width || p.y >= pc.height) return;
  vec2 ndc = vec2(2.0 * (float(p.x) + 0.5) / float(pc.width) - 1.0, 1.0 - 2.0 * (float(p.y) + 0.5) / float(pc.height));
  vec3 o = vec3(0.0, 0.0, 3.0);
  vec3 dir = normalize(vec3(ndc * pc.tanHalfFov, -1.0));
  float b = dot(o, dir), c = dot(o, o) - 1.0, disc = b * b - c;
  if (disc < 0.0) return;
  vec3 N = normalize(o + dir * (-b - sqrt(disc)));
  vec3 V = -dir;
  float s = N.z >= 0.0 ? 1.0 : -1.0, aa = -1.0 / (s + N.z), bb = N.x * N.y * aa;
  vec3 X = vec3(1.0 + s * N.x * N.x * aa, s * bb, -s * N.x), Y = vec3(bb, s + N.y * N.y * aa, -N.y);
  uint seed = (p.y * pc.width + p.x) * 9781u + pc.firstSample * 6271u;
  vec3 sum = vec3(0.0);
  for (uint i = 0u; i < pc.count; ++i) {
    float u1 = rnd(seed), u2 = rnd(seed);
    float r = sqrt(u1), phi = 2.0 * PI * u2, z = sqrt(max(0.0, 1.0 - u1));
    vec3 L = X * (r * cos(phi)) + Y * (r * sin(phi)) + N * z;
    float pdf = z / PI;
    sum += ggx(L, V, N) * textureLod(envMap, L, 0.0).rgb * (pdf > 0.0 ? z / pdf : 0.0);
  }
  accum[p.y * pc.width + p.x] += vec4(sum, float(pc.count));
}
