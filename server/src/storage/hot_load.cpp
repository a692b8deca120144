#include "storage/hot_load.h"

#include <chrono>
#include <cstdio>

namespace brdfa::server {

void HotLoader::start(std::shared_ptr<Renderer> renderer, std::vector<std::shared_ptr<const BrdfEntry>> entries) {
  stop();
  stop_ = false;
  done_ = false;
  enabled_ = true;
  brdfs_ = static_cast<int>(entries.size());
  visited_ = 0;
  pipelines_ = 0;
  thread_ = std::thread([this, renderer = std::move(renderer), entries = std::move(entries)] {
    const auto t0 = std::chrono::steady_clock::now();
    auto elapsed = [&] {
      return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    };
    for (const auto& entry : entries) {
      if (stop_) break;
      Result<int> built = renderer->preloadFromCache(*entry->definition);
      if (built)
        pipelines_ += built.value();
      else  // not fatal: the BRDF compiles (and reports the error) on first use as always
        std::fprintf(stderr, "warning: hot-load: %s: %s\n", entry->name.c_str(), built.error().message.c_str());
      ++visited_;
      ms_ = elapsed();
    }
    ms_ = elapsed();
    done_ = true;
    std::fprintf(stderr, "hot-load: %d pipelines from cached SPIR-V for %d BRDFs in %.0f ms\n", pipelines_.load(),
                 visited_.load(), ms_.load());
  });
}

void HotLoader::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

HotLoadProgress HotLoader::progress() const {
  HotLoadProgress p;
  p.enabled = enabled_;
  p.done = done_;
  p.brdfs = brdfs_;
  p.visited = visited_;
  p.pipelines = pipelines_;
  p.ms = ms_;
  return p;
}

}  // namespace brdfa::server
