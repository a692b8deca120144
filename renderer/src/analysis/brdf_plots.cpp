// plotBrdf (brdf_plots.h): the directions of each plot, and the values the device returns.
#include "brdfa/brdf_plots.h"

#include <chrono>
#include <cmath>
#include <limits>

namespace brdfa {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMaxThetaDeg = 89.9;  // incident and view angles: on the horizon the albedo is 0/0
constexpr uint32_t kMinAlbedoSamples = 2048, kMaxAlbedoSamples = 1u << 18;
constexpr size_t kMaxViews = 91;

double rad(double deg) { return deg * kPi / 180.0; }

Vec3 vec(double x, double y, double z) { return {float(x), float(y), float(z)}; }

// Exactly on the horizon at 90 degrees (float cos(pi/2) is not 0).
Vec3 polar(double thetaDeg, double phiDeg) {
  const double t = rad(thetaDeg), p = rad(phiDeg);
  const double s = std::fabs(thetaDeg) >= 90 ? (thetaDeg > 0 ? 1.0 : -1.0) : std::sin(t);
  const double z = std::fabs(thetaDeg) >= 90 ? 0.0 : std::cos(t);
  return vec(s * std::cos(p), s * std::sin(p), z);
}

std::vector<double> steps(double from, double to, int n) {
  std::vector<double> v(n);
  for (int i = 0; i < n; ++i) v[i] = n == 1 ? from : from + (to - from) * i / (n - 1);
  return v;
}

Result<void> invalid(const std::string& field, const std::string& message) {
  return makeError(ErrorCode::InvalidArgument, field + ": " + message, field);
}

}  // namespace

Result<void> checkPlotRequest(const PlotRequest& r) {
  if (r.resolution != 0 && r.kind != PlotKind::Albedo && (r.resolution < 3 || r.resolution > maxResolution(r.kind)))
    return invalid("resolution", "must be 3.." + std::to_string(maxResolution(r.kind)) + " for a " +
                                     plotKindName(r.kind) + " plot (0 takes " +
                                     std::to_string(defaultResolution(r.kind)) + ")");
  if (!(r.thetaIDeg >= 0 && r.thetaIDeg <= kMaxThetaDeg)) return invalid("theta_i", "must be 0..89.9 degrees");
  if (!std::isfinite(r.phiDDeg)) return invalid("phi_d", "must be a number of degrees");
  if (r.viewDeg.size() > kMaxViews) return invalid("theta_v", "at most " + std::to_string(kMaxViews) + " angles");
  for (double v : r.viewDeg)
    if (!(v >= 0 && v <= kMaxThetaDeg)) return invalid("theta_v", "every angle must be 0..89.9 degrees");
  if (r.samples < kMinAlbedoSamples || r.samples > kMaxAlbedoSamples)
    return invalid("samples",
                   "must be " + std::to_string(kMinAlbedoSamples) + ".." + std::to_string(kMaxAlbedoSamples));
  return {};
}

const char* plotKindName(PlotKind kind) {
  switch (kind) {
    case PlotKind::Polar: return "polar";
    case PlotKind::Lobe: return "lobe";
    case PlotKind::Albedo: return "albedo";
    case PlotKind::Slice: return "slice";
  }
  return "polar";
}

bool plotKindFromName(const std::string& name, PlotKind& kind) {
  for (PlotKind k : {PlotKind::Polar, PlotKind::Lobe, PlotKind::Albedo, PlotKind::Slice})
    if (name == plotKindName(k)) {
      kind = k;
      return true;
    }
  return false;
}

int defaultResolution(PlotKind kind) {
  switch (kind) {
    case PlotKind::Polar: return 181;
    case PlotKind::Lobe: return 46;
    case PlotKind::Slice: return 91;
    case PlotKind::Albedo: return 19;
  }
  return 0;
}

int maxResolution(PlotKind kind) {
  switch (kind) {
    case PlotKind::Polar: return 1801;
    case PlotKind::Lobe: return 181;
    case PlotKind::Slice: return 256;
    case PlotKind::Albedo: return int(kMaxViews);
  }
  return 0;
}

std::vector<DirectionPair> plotPairs(const PlotRequest& r, std::vector<PlotAxis>& axes) {
  const int n = r.resolution > 0 ? r.resolution : defaultResolution(r.kind);
  const Vec3 light = polar(r.thetaIDeg, 180.0);
  std::vector<DirectionPair> pairs;
  axes.clear();
  switch (r.kind) {
    case PlotKind::Polar: {
      axes.push_back({"theta_deg", steps(-90, 90, n)});
      const double ti = rad(r.thetaIDeg);
      const double rx = std::sin(ti), rz = std::cos(ti);  // the mirror direction R
      for (double t : axes[0].values) pairs.push_back({light, polar(t, 0.0)});
      for (double t : axes[0].values) {
        // cos t R + sin t Y; at |t| = 90 exactly +-Y (on the horizon).
        const double c = std::fabs(t) >= 90 ? 0.0 : std::cos(rad(t));
        const double s = std::fabs(t) >= 90 ? (t > 0 ? 1.0 : -1.0) : std::sin(rad(t));
        pairs.push_back({light, vec(c * rx, s, c * rz)});
      }
      break;
    }
    case PlotKind::Lobe: {
      axes.push_back({"theta_deg", steps(0, 90, n)});
      std::vector<double> phi(4 * (n - 1));
      for (size_t i = 0; i < phi.size(); ++i) phi[i] = 360.0 * double(i) / double(phi.size());
      axes.push_back({"phi_deg", phi});
      for (double p : axes[1].values)
        for (double t : axes[0].values) pairs.push_back({light, polar(t, p)});
      break;
    }
    case PlotKind::Slice: {
      axes.push_back({"theta_h_deg", steps(0, 90, n)});
      axes.push_back({"theta_d_deg", steps(0, 90, n)});
      const double pd = rad(r.phiDDeg);
      for (double td : axes[1].values)
        for (double th : axes[0].values) {
          // D about H = +z, then turned by theta_h about +y so that +z goes to H.
          const double sd = std::sin(rad(td)), cd = std::cos(rad(td));
          const double dx = sd * std::cos(pd), dy = sd * std::sin(pd), dz = cd;
          const double ch = std::cos(rad(th)), sh = std::sin(rad(th));
          // Directions within 1e-9 of the horizon are put on it (cos(pi/2) is 6e-17, not 0): the
          // BRDF has no value there (1 / cos), and the plot shows none.
          auto turn = [&](double x, double y, double z) {
            double w = -x * sh + z * ch;
            if (std::fabs(w) < 1e-9) w = 0;
            return vec(x * ch + z * sh, y, w);
          };
          pairs.push_back({turn(dx, dy, dz), turn(-dx, -dy, dz)});
        }
      break;
    }
    case PlotKind::Albedo: {
      std::vector<double> views = r.viewDeg;
      if (views.empty()) {
        for (int i = 0; i <= 85; i += 5) views.push_back(i);
        views.push_back(89);
      }
      axes.push_back({"theta_v_deg", views});
      for (double v : views) pairs.push_back({vec(0, 0, 1), polar(v, 0.0)});
      break;
    }
  }
  return pairs;
}

Result<Plot> plotBrdf(Renderer& renderer, const BrdfDefinition& brdf, const std::vector<ParamSetting>& settings,
                      const PlotRequest& request) {
  if (Result<void> ok = checkPlotRequest(request); !ok) return ok.takeError();
  const auto t0 = std::chrono::steady_clock::now();
  Plot plot;
  plot.kind = request.kind;
  std::vector<DirectionPair> pairs = plotPairs(request, plot.axes);
  if (request.kind == PlotKind::Polar) plot.planes = {"incidence", "perpendicular"};

  if (request.kind == PlotKind::Albedo) {
    std::vector<Vec3> views;
    for (const DirectionPair& p : pairs) views.push_back(p.view);
    auto albedo = renderer.estimateAlbedo(brdf, settings, views, request.samples);
    if (!albedo) return albedo.takeError();
    plot.estimator = albedoEstimatorName(brdf);
    for (size_t s = 0; s < settings.size(); ++s) {
      std::vector<Vec3> mean, err;
      for (size_t v = 0; v < views.size(); ++v) {
        const AlbedoEstimate& e = albedo.value()[s * views.size() + v];
        mean.push_back(e.mean);
        err.push_back(e.stdError);
        plot.samples = e.samples;
      }
      plot.values.push_back(std::move(mean));
      plot.stdError.push_back(std::move(err));
    }
  } else {
    auto values = renderer.evaluateBrdf(brdf, settings, pairs);
    if (!values) return values.takeError();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (size_t s = 0; s < settings.size(); ++s) {
      std::vector<Vec3> row(values.value().begin() + s * pairs.size(), values.value().begin() + (s + 1) * pairs.size());
      for (size_t p = 0; p < pairs.size(); ++p) {
        const float nv = pairs[p].view[2], nl = pairs[p].light[2];
        if (request.kind == PlotKind::Slice && (nv <= 0 || nl <= 0)) row[p] = {nan, nan, nan};  // below the horizon
        if (request.cosine && request.kind != PlotKind::Slice)
          for (float& c : row[p]) c *= std::max(nv, 0.0f);
      }
      plot.values.push_back(std::move(row));
    }
  }
  plot.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return plot;
}

}  // namespace brdfa
