// Renderer::checkBrdf: numeric checks of a BRDF on the device (BrdfCheckReport in renderer.h;
// shaders/kernels/check.comp.glsl).
#include <chrono>
#include <cmath>
#include <cstdio>

#include "analysis/check_kernel.h"
#include "analysis/device_checks.h"

namespace brdfa {

namespace {

constexpr uint32_t kViews = 40;  // BRDFA_VIEWS in check.comp.glsl

// The parameter settings checked: all defaults, then each parameter alone at its minimum and
// its maximum (colors at black and white, bools at false and true).
std::vector<std::map<std::string, Vec3>> checkSettings(const BrdfDefinition& brdf) {
  std::vector<std::map<std::string, Vec3>> settings(1);
  for (const BrdfParam& p : brdf.params) {
    Vec3 lo{p.min, p.min, p.min}, hi{p.max, p.max, p.max};
    if (p.type == ParamType::Color) lo = {0, 0, 0}, hi = {1, 1, 1};
    if (p.type == ParamType::Bool) lo = {0, 0, 0}, hi = {1, 0, 0};
    settings.push_back({{p.name, lo}});
    settings.push_back({{p.name, hi}});
  }
  return settings;
}

// The check kernel's grid (check.comp.glsl): polar angles of V and L, azimuths 45 degrees apart.
constexpr double kCheckThetaDeg[10] = {0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 85.0, 89.0, 89.9, 90.0};

std::string number(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%.4g", v);
  return s;
}

std::string direction(const char* name, double thetaDeg, double phiDeg) {
  return std::string(name) + " (theta " + number(thetaDeg) + " deg, phi " + number(phiDeg) + " deg)";
}

// One entry of checkSettings, for a person: "defaults" or "roughness = 0.001 (others default)".
std::string describeSetting(const std::map<std::string, Vec3>& setting, const BrdfDefinition& brdf) {
  if (setting.empty()) return "all parameters at their defaults";
  std::string out;
  for (const auto& [name, v] : setting) {
    const BrdfParam* p = brdf.findParam(name);
    const bool color = p && p->type == ParamType::Color;
    out += (out.empty() ? "" : ", ") + name + " = " +
           (color ? "[" + number(v[0]) + ", " + number(v[1]) + ", " + number(v[2]) + "]" : number(v[0]));
  }
  return out + " (others at their defaults)";
}

// The three properties a file may claim, judged against BrdfCheckReport's limits.
std::vector<ClaimVerdict> claimVerdicts(const BrdfCheckReport& r, const BrdfClaims& claims) {
  std::vector<ClaimVerdict> out(3);
  out[0] = {"reciprocity", claims.reciprocity, r.maxReciprocityError <= BrdfCheckReport::kReciprocityLimit,
            "largest relative error " + number(r.maxReciprocityError) + " (limit " +
                number(BrdfCheckReport::kReciprocityLimit) + ")" +
                (r.worstReciprocity.empty() ? "" : ", " + r.worstReciprocity)};
  out[1] = {"energy-conservation", claims.energyConservation, r.albedoAboveOne == 0,
            std::to_string(r.albedoAboveOne) + " (view, setting) pairs with albedo above 1 by more than " +
                number(BrdfCheckReport::kAlbedoSigmas) + " standard errors; largest albedo " +
                (r.worstAlbedo.empty() ? "0" : r.worstAlbedo)};
  out[2] = {"non-negativity", claims.nonNegativity, r.negativeCount == 0,
            std::to_string(r.negativeCount) + " negative values" +
                (r.negativeCount && !r.firstBadValue.empty() ? "; first bad value: " + r.firstBadValue : "")};
  return out;
}
}  // namespace

namespace analysis {

Result<BrdfCheckReport> checkBrdf(const CheckDevice& device, const BrdfDefinition& brdf) {
  const auto t0 = std::chrono::steady_clock::now();
  BrdfCheckReport report;
  const std::vector<std::map<std::string, Vec3>> settings = checkSettings(brdf);
  size_t setting = 0;  // consume() is called once per setting, in order
  auto ran = runCheckKernel(device, brdf, "check.comp.glsl", kViews, kViews * 4, settings, [&](const float* out) {
    const std::string where = describeSetting(settings[setting++], brdf);
    for (uint32_t v = 0; v < kViews; ++v) {
      const float* counts = out + 16 * v;
      const float* albedo = counts + 4;
      const float* worst = counts + 8;
      const float* first = counts + 12;
      const std::string view = direction("V", kCheckThetaDeg[v % 10], 45.0 * (v / 10));
      auto light = [](float at) { return direction("L", kCheckThetaDeg[int(at) / 8], 45.0 * (int(at) % 8)); };
      report.nanCount += static_cast<uint64_t>(counts[0]);
      report.infCount += static_cast<uint64_t>(counts[1]);
      report.negativeCount += static_cast<uint64_t>(counts[2]);
      report.evaluations += static_cast<uint64_t>(counts[3]);
      report.leftOut += static_cast<uint64_t>(albedo[3]);
      if (std::isfinite(albedo[0]) && albedo[0] > report.maxAlbedo) {
        report.maxAlbedo = albedo[0];
        report.maxAlbedoStdError = albedo[1];
        report.worstAlbedo =
            number(albedo[0]) + " +- " + number(albedo[1]) + " (standard error) at " + view + ", " + where;
      }
      // Only a significant excess counts: the estimate's own error bar says how far it may be
      // off (BrdfCheckReport's limits).
      if (albedo[0] - BrdfCheckReport::kAlbedoSigmas * albedo[1] > 1.0 + BrdfCheckReport::kAlbedoSlack)
        ++report.albedoAboveOne;
      if (albedo[2] > report.maxReciprocityError) {
        report.maxReciprocityError = albedo[2];
        report.worstReciprocity = number(albedo[2]) + " at " + view + ", " + light(worst[0]) + ", " + where +
                                  ": f(L,V) = " + number(worst[1]) + ", f(V,L) = " + number(worst[2]);
      }
      if (first[3] > 0 && report.firstBadValue.empty()) {
        const char* kind = first[3] == 1 ? "NaN" : first[3] == 2 ? "Inf" : "a negative value";
        const std::string at = worst[3] >= 100 ? "an albedo sample (f cos / pdf of a drawn L)" : light(worst[3]);
        report.firstBadValue = std::string(kind) + " (" + number(first[0]) + ", " + number(first[1]) + ", " +
                               number(first[2]) + ") at " + view + ", " + at + ", " + where;
      }
    }
  });
  if (!ran) return ran.takeError();
  report.claims = claimVerdicts(report, brdf.claims);
  report.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

}  // namespace analysis

}  // namespace brdfa
