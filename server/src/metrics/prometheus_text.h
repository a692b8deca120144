// Writes the Prometheus text exposition format (version 0.0.4): families with # HELP and
// # TYPE, samples with escaped label values, histograms as cumulative _bucket{le=...} series
// with _sum and _count. Knows nothing of what is measured.
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "brdfa/duration_histogram.h"

namespace brdfa::server {

using PrometheusLabels = std::vector<std::pair<std::string, std::string>>;

class PrometheusText {
 public:
  // Starts a family. `type`: counter, gauge or histogram; `help` is escaped as the format asks.
  void family(std::string_view name, std::string_view type, std::string_view help);
  // One sample line; NaN and infinities are written as the format spells them.
  void sample(std::string_view name, double value, const PrometheusLabels& labels = {});
  // One histogram series of the family `name` (started with family(name, "histogram", ...)).
  void histogram(std::string_view name, const DurationHistogram& h, const PrometheusLabels& labels = {});

  const std::string& text() const { return out_; }

  static constexpr const char* kContentType = "text/plain; version=0.0.4; charset=utf-8";

 private:
  std::string out_;
};

}  // namespace brdfa::server
