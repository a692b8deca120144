// The Analysis tab's plots of a BRDF (the curves of Disney's BRDF Explorer), built
// from Renderer::evaluateBrdf and Renderer::estimateAlbedo. No HTTP here: the server turns a
// Plot into JSON or CSV.
//
// Frame: N = +z, X = +x, Y = +y. The incident direction L of the polar and lobe plots lies at
// polar angle theta_i and azimuth 180 degrees, L = (-sin theta_i, 0, cos theta_i), so its
// mirror direction is R = (sin theta_i, 0, cos theta_i).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "brdfa/renderer.h"

namespace brdfa {

enum class PlotKind {
  // f(L, V) against V in two planes through N, at signed angles theta (degrees) in -90..90:
  // the plane of incidence, V = (sin theta, 0, cos theta) (the mirror direction at theta =
  // +theta_i), and the plane through R perpendicular to it, V = cos theta R + sin theta Y.
  Polar,
  // f(L, V) over the hemisphere of V: V = (sin t cos p, sin t sin p, cos t) at t in 0..90 and
  // p in 0..360 (exclusive) degrees, in equal steps (4 (n - 1) azimuths for n polar angles); a
  // mesh vertex is V times its value.
  Lobe,
  // Directional albedo against the view's polar angle theta_v (V = (sin theta_v, 0, cos
  // theta_v)), with its standard error (Renderer::estimateAlbedo).
  Albedo,
  // f over (theta_h, theta_d) at a fixed phi_d (Rusinkiewicz 1998 coordinates, the image slice
  // of Burley 2012 and the Explorer): H = (sin theta_h, 0, cos theta_h), L the direction at
  // (theta_d, phi_d) about H and V its reflection about H. Pairs with L or V below the horizon
  // have no value (NaN).
  Slice,
};
const char* plotKindName(PlotKind kind);  // "polar" | "lobe" | "albedo" | "slice"
bool plotKindFromName(const std::string& name, PlotKind& kind);

struct PlotRequest {
  PlotKind kind = PlotKind::Polar;
  double thetaIDeg = 30;        // polar, lobe: 0..89.9
  bool cosine = false;          // polar, lobe: f (N.V) instead of f
  int resolution = 0;           // points per axis; 0 takes the kind's default (defaultResolution)
  double phiDDeg = 90;          // slice
  std::vector<double> viewDeg;  // albedo: 0..89.9; empty takes 0, 5, ..., 85, 89
  uint32_t samples = 32768;     // albedo: per view, at least 2048
};

// Points per axis when PlotRequest::resolution is 0, and the largest accepted.
int defaultResolution(PlotKind kind);  // polar 181, lobe 46 polar angles (and 4 x 45 azimuths), slice 91
int maxResolution(PlotKind kind);      // polar 1801, lobe 181, slice 256

struct PlotAxis {
  std::string name;  // "theta_deg", "phi_deg", "theta_h_deg", "theta_d_deg", "theta_v_deg"
  std::vector<double> values;
};

struct Plot {
  PlotKind kind = PlotKind::Polar;
  // Polar: {theta_deg}; lobe: {theta_deg, phi_deg}; slice: {theta_h_deg, theta_d_deg};
  // albedo: {theta_v_deg}.
  std::vector<PlotAxis> axes;
  std::vector<std::string> planes;  // polar: {"incidence", "perpendicular"}
  // Per setting, in request order, row-major over the axes, the first axis fastest:
  // polar: plane * n + i; lobe: phi * nTheta + theta; slice: theta_d * nThetaH + theta_h.
  std::vector<std::vector<Vec3>> values;
  std::vector<std::vector<Vec3>> stdError;  // albedo only
  std::string estimator;                    // albedo only (albedoEstimatorName)
  uint64_t samples = 0;                     // albedo only: per view
  double ms = 0;                            // device and host time of this plot
};

// InvalidArgument naming the field ("theta_i", "resolution", ...) when a value is out of range.
Result<void> checkPlotRequest(const PlotRequest& request);

// Checks the request (checkPlotRequest) and computes the plot for every
// setting of `brdf`. Errors of the renderer (CompileError, Unsupported for legacy files,
// RenderBudget) pass through.
Result<Plot> plotBrdf(Renderer& renderer, const BrdfDefinition& brdf, const std::vector<ParamSetting>& settings,
                      const PlotRequest& request);

// The directions behind each plot (exposed for tests): the pairs evaluated, in value order.
std::vector<DirectionPair> plotPairs(const PlotRequest& request, std::vector<PlotAxis>& axes);

}  // namespace brdfa
