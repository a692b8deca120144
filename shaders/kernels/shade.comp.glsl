// The integrator: Monte Carlo estimate of reflected radiance for one object's pixels,
//   L_o(V) = 1/N * sum_k f(L_k, V) * L_env(L_k) * max(0, N.L_k) / q(L_k),
// with L_k drawn from the density q of this program's strategy; every strategy is unbiased:
//  - cosine, uniform: over the hemisphere, cos/q in closed form (pi and 2 pi cos);
//  - brdf: the file's own sampleBRDF(), which returns f and q;
//  - environment: lib/environment_sampling.glsl, q in proportion to the map's luminance;
//  - mis: multiple importance sampling of the environment and the BRDF side (the file's
//    sampler when it also has pdfBRDF, else cosine) with the balance heuristic (Veach 1997,
//    section 9.2), over a deterministic mixture: a fraction c of a pixel's samples come from the
//    environment, the rest from the BRDF side, and every sample is weighted by the mixture
//    density q = (1 - c) p_brdf + c p_env. Which strategy sample j uses follows the Kronecker
//    sequence frac(j c + phi) < c with a random phi per pixel and half: each sample is drawn
//    from the mixture exactly (so the estimate is unbiased for every j and every pass split),
//    yet the counts per strategy are c N to within one, without the noise of a coin flip.
//    c is chosen per pixel from how concentrated each side is (misEnvironmentFraction), in
//    eighths; it only changes the variance.
// Samples that are NaN or Inf are dropped and counted, never accumulated, and the pixel's mean
// divides by the samples kept. Sample i of a pixel goes to half accumulator i & 1 (see
// lib/random.glsl): the halves are independent estimates, and the resolve measures the error
// from their difference.
//
// A BRDFA Engine file (BRDFA_LEGACY_RENDER) is run as that engine ran it instead: the pixel is
// the plain average of its render(L, N, V, texCoord, worldToLocal) over uniform hemisphere
// samples, render() doing its own environment lookup and cosine, with the engine's
// worldToLocal (below) and its PI and LI (program_assembler.cpp). That is not an estimate of
// L_o (it lacks the 2 pi of the uniform pdf, and whatever the file leaves out); it reproduces
// the engine's images, and such files are marked "legacy" and never analysed.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#if defined(BRDFA_SAMPLING_MIS)
// Density of the BRDF side's draws at L.
float brdfa_brdfSidePdf(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {
#if defined(BRDFA_MIS_FILE_SAMPLER)
  return pdfBRDF(L, V, N, X, Y);
#else
  return max(dot(N, L), 0.0) / BRDFA_PI;
#endif
}

// The fraction c of this pixel's samples drawn from the environment. Each side's concentration
// is a density: the BRDF side's at the mirror direction R (its lobe's peak for glossy files,
// cos/pi for diffuse ones); the environment's at R (what a narrow lobe sees) and over the whole
// map (its effective density, what a wide lobe sees). Half and half unless one side clearly
// wins: a wide lobe (peak under 1/sr) under a map 8x more concentrated takes 7/8 from the map
// (a Lambertian under a sun); a narrow lobe (peak over 8/sr) 8x more concentrated than the map
// around R takes 7/8 from the BRDF side (a near-mirror away from the sun). Measured in
// bench/bench_sampling.cpp (GGX 0.2 in the sky, mis against cosine at equal time): c = 1/2 gave
// 8.1x, 3/8 7.8x, 1/4 to 3/4 by the map's density at R 4.0x, and a continuous rule (the
// squared ratio of the concentrations, mostly 7/8 there) 3.2x. c only changes the variance: the
// bounds [1/8, 7/8] cap the cost of a wrong guess at 8/7 for the side that should have had all
// samples, 8x for the other.
float brdfa_misEnvironmentFraction(vec3 V, vec3 N, vec3 X, vec3 Y) {
  vec3 R = reflect(-V, N);
  float lobe = brdfa_brdfSidePdf(R, V, N, X, Y);
  // guard: a user's pdfBRDF may return NaN, Inf or a negative value here. Every c keeps the
  // estimate unbiased, so any of them may pick c: NaN fails every comparison (1/2), a negative
  // value reads as a wide lobe, Inf as a narrow one.
  if (lobe < 1.0 && brdfa_environmentConcentration() > 8.0 * lobe) return 0.875;
  if (lobe > 8.0 && lobe > 8.0 * brdfa_environmentPdf(R)) return 0.125;
  return 0.5;
}
#endif

void main() {
  bool preview = (brdfa_pc.target.w & 2u) != 0u;  // lib/shade_pixel.glsl
  uvec2 base, p, surface;
  uint blockMask;
  if (!brdfa_shadedPixel(preview, base, blockMask, p, surface)) return;
  vec3 N, V, X, Y;
  brdfa_surfaceFrame(p, surface, N, V, X, Y);
#if defined(BRDFA_LEGACY_RENDER)
  // render()'s worldToLocal, built as the BRDFA Engine built it (Mohido/BRDFA_Engine,
  // BRDFA_Engine/shaders/main.frag at commit 97f1b36eb3b864d242055928a29cc76c31274a5b):
  // transpose(mat3(T, N, B)) with T = normalize(cross(V, N)) and B = normalize(cross(T, N)),
  // i.e. rows T, N, B: worldToLocal * v = (T.v, N.v, B.v), so N maps to (0, 1, 0) and V to
  // (0, N.V, -|V x N|). The frame turns with V and never reads the surface's tangent. Where V is
  // along N the engine's T is NaN; X (a unit tangent, orthogonal to N) stands in there.
  vec3 engineT = cross(V, N);
  float engineT2 = dot(engineT, engineT);
  engineT = engineT2 > 1e-12 ? engineT * inversesqrt(engineT2) : X;
  mat3 worldToLocal = transpose(mat3(engineT, N, normalize(cross(engineT, N))));
#endif

  uint seed = brdfa_pc.target.y;  // render.seed
  uvec4 rotationA = brdfa_halfRotation(p, 0u, seed), rotationB = brdfa_halfRotation(p, 1u, seed);
#if defined(BRDFA_SAMPLING_ENVIRONMENT) || defined(BRDFA_SAMPLING_MIS)
  brdfa_environmentBegin();
#endif
#if defined(BRDFA_SAMPLING_MIS)
  // c in eighths (0.125 .. 0.875), exact in 32-bit fixed point, so the strategy test below and
  // the weight use exactly the same c. The phase is one random number per half for the whole
  // image: neighbouring pixels with the same c then pick the same strategy for the same sample,
  // so the SIMD lanes of a CPU device (and the threads of a GPU warp) rarely diverge. Each sample
  // is still drawn from the mixture exactly (the phase is uniform), and the halves stay
  // independent (each has its own phase).
  float cEnv = clamp(round(brdfa_misEnvironmentFraction(V, N, X, Y) * 8.0), 1.0, 7.0) * 0.125;
  uint envShare = uint(cEnv * 8.0) << 29u;
  float cBrdf = 1.0 - cEnv;
  uvec2 phase = uvec2(brdfa_hash(seed ^ 0xa511e9b3u), brdfa_hash(seed ^ 0x63d83595u));
#endif
  uint first = brdfa_pc.frame.z;
  uint count = brdfa_pc.frame.w;
  // Sums of all kept samples and of half B's (half A's is the difference): no branch or
  // dynamically indexed array in the loop, which a CPU device turns into per-lane memory.
  vec3 sumAll = vec3(0.0), sumB = vec3(0.0);
  uint keptAll = 0u, keptB = 0u;
  uint dropped = 0u;
  for (uint s = 0u; s < count; ++s) {
    uint i = first + s;
    uint h = i & 1u;
    uint j = i >> 1u;
    uvec4 u = brdfa_sample4D(h == 0u ? rotationA : rotationB, j);
#if defined(BRDFA_LEGACY_RENDER)
    float unusedWeight;
    vec3 l = brdfa_sampleUniformHemisphere(brdfa_unorm2(u.xy), unusedWeight);
    vec3 L = X * l.x + Y * l.y + N * l.z;
    vec3 c = render(L, N, V, texCoord, worldToLocal);
#elif defined(BRDFA_SAMPLING_BRDF)
    // The file's own importance sampler: it returns f(L, V) and the solid-angle pdf of L.
    vec3 L;
    float pdf;
    vec3 f = sampleBRDF(brdfa_unorm2(u.xy), V, N, X, Y, L, pdf);
    // guard: pdf = 0 marks a direction the sampler rejected (below the horizon): it
    // contributes 0, and dividing would give 0/0.
    vec3 c = pdf > 0.0 ? f * brdfa_environmentUnit(L) * (max(dot(N, L), 0.0) / pdf) : vec3(0.0);
#elif defined(BRDFA_SAMPLING_ENVIRONMENT)
    float pdf;
    vec3 L = brdfa_sampleEnvironment(u, pdf);
    float NoL = dot(N, L);
    // Directions below the horizon are drawn too (the map is sampled over the whole sphere)
    // and contribute 0; the BRDF is not evaluated there.
    vec3 c = NoL > 0.0 ? BRDF(L, V, N, X, Y) * brdfa_environmentUnit(L) * (NoL / pdf) : vec3(0.0);
#elif defined(BRDFA_SAMPLING_MIS)
    // Written without branches: a CPU device (lavapipe) runs both sides of every if for all
    // its SIMD lanes, so a branch per strategy would cost both strategies, two table reads and
    // two BRDF evaluations per sample. Here a sample costs two table reads, one BRDF() and one
    // density of each side, whichever strategy drew it.
    bool fromEnv = j * envShare + phase[h] < envShare;
    // The BRDF side's direction. Its value and density are taken below at whichever direction
    // is used, so both strategies weigh a direction the same way (the file's sampler returns
    // the same f and pdf; only its pdf = 0, a rejected draw, is kept).
    vec3 Lb;
#if defined(BRDFA_MIS_FILE_SAMPLER)
    float pdfDrawn;
    sampleBRDF(brdfa_unorm2(u.xy), V, N, X, Y, Lb, pdfDrawn);
    bool rejected = !fromEnv && !(pdfDrawn > 0.0);
#else
    float unusedWeight;
    vec3 l = brdfa_sampleCosineHemisphere(brdfa_unorm2(u.xy), unusedWeight);
    Lb = X * l.x + Y * l.y + N * l.z;
    bool rejected = false;
#endif
    // Both strategies' directions, then one density read for the one used: the alias step
    // reads the picked cell's entry, the density read the entry of the cell L lies in. A
    // BRDF-side sample's alias step reads cell 0 instead of a random cell: its result is not
    // used, and the table's random reads are what costs on a CPU (cache misses).
    uint cellE = brdfa_environmentAliasStep(fromEnv ? brdfa_environmentPick(u.x) : 0u, u.y);
    float majorE, majorB;
    vec3 Le = brdfa_environmentCellPoint(cellE, u.zw, majorE);
    uint cellB = brdfa_environmentCell(Lb, majorB);
    vec3 L = fromEnv ? Le : Lb;
    float pdfEnv = brdfa_environmentCellPdf(fromEnv ? cellE : cellB, fromEnv ? majorE : majorB);
    vec3 f = BRDF(L, V, N, X, Y);
    float pdfBrdf = brdfa_brdfSidePdf(L, V, N, X, Y);
    float NoL = dot(N, L);
    // The balance heuristic over the mixture: f L cos / ((1 - c) p_brdf + c p_env). The
    // environment's density is never 0 (its table has a floor), so neither is the sum where
    // NoL > 0. Directions below the horizon (drawn from the map, or rejected by the file's
    // sampler) contribute 0 whatever BRDF() returned there.
    vec3 c = NoL > 0.0 && !rejected
                 ? f * brdfa_environmentUnit(L) * (NoL / (cBrdf * max(pdfBrdf, 0.0) + cEnv * pdfEnv))  // guard: a user pdf < 0
                 : vec3(0.0);
#else
    float weight;  // cos / pdf
    vec3 l = brdfa_sampleHemisphere(brdfa_unorm2(u.xy), weight);
    vec3 L = X * l.x + Y * l.y + N * l.z;
    vec3 c = BRDF(L, V, N, X, Y) * brdfa_environmentUnit(L) * weight;
#endif
    if (!brdfa_sampleKept(c)) {  // NaN or infinite (lib/shade_pixel.glsl)
      ++dropped;
      continue;
    }
    brdfa_addSample(c, h, sumAll, sumB, keptAll, keptB);
  }
  vec4 valueA, valueB;
  brdfa_halfValues(sumAll, sumB, keptAll, keptB, valueA, valueB);
  brdfa_writeShaded(base, blockMask, preview, valueA, valueB);
  if (dropped != 0u) atomicAdd(brdfa_nanSamples, dropped);
}
