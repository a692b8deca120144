#include "metrics/prometheus_text.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace brdfa::server {

namespace {

std::string escaped(std::string_view text, bool quotes) {
  std::string out;
  for (char c : text) {
    if (c == '\\')
      out += "\\\\";
    else if (c == '\n')
      out += "\\n";
    else if (c == '"' && quotes)
      out += "\\\"";
    else
      out += c;
  }
  return out;
}

std::string number(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "+Inf" : "-Inf";
  char buf[40];
  // Whole numbers (counts, bytes) exactly; others with enough digits to round-trip.
  if (v == std::floor(v) && std::fabs(v) < 1e15)
    std::snprintf(buf, sizeof buf, "%.0f", v);
  else {
    // The shortest of 15 or 17 digits that reads back as v: le="0.0025", not 0.0025000000000000001.
    std::snprintf(buf, sizeof buf, "%.15g", v);
    if (std::strtod(buf, nullptr) != v) std::snprintf(buf, sizeof buf, "%.17g", v);
  }
  return buf;
}

std::string labelText(const PrometheusLabels& labels) {
  if (labels.empty()) return {};
  std::string out = "{";
  for (size_t i = 0; i < labels.size(); ++i) {
    if (i) out += ',';
    out += labels[i].first + "=\"" + escaped(labels[i].second, true) + '"';
  }
  return out + '}';
}

}  // namespace

void PrometheusText::family(std::string_view name, std::string_view type, std::string_view help) {
  out_ += "# HELP " + std::string(name) + ' ' + escaped(help, false) + '\n';
  out_ += "# TYPE " + std::string(name) + ' ' + std::string(type) + '\n';
}

void PrometheusText::sample(std::string_view name, double value, const PrometheusLabels& labels) {
  out_ += std::string(name) + labelText(labels) + ' ' + number(value) + '\n';
}

void PrometheusText::histogram(std::string_view name, const DurationHistogram& h, const PrometheusLabels& labels) {
  const std::string base(name);
  uint64_t cumulative = 0;
  for (size_t i = 0; i < h.counts.size(); ++i) {
    cumulative += h.counts[i];
    PrometheusLabels withLe = labels;
    withLe.emplace_back("le",
                        i < DurationHistogram::kBoundsSec.size() ? number(DurationHistogram::kBoundsSec[i]) : "+Inf");
    sample(base + "_bucket", static_cast<double>(cumulative), withLe);
  }
  sample(base + "_sum", h.sumSec, labels);
  sample(base + "_count", static_cast<double>(h.count), labels);
}

}  // namespace brdfa::server
