// --hot-load: the BRDFA Engine's "hot start" (its loadPipelines(): start from the cache,
// without compiling what is not cached). After start-up a background thread builds the shading
// pipelines of every library BRDF whose SPIR-V is already cached, so a BRDF used before is
// instant on its first use; nothing is compiled from GLSL, and the server answers requests
// meanwhile. Without the flag nothing is prepared at start (BRDFs compile on first use).
#pragma once

#include <atomic>
#include <memory>
#include <thread>
#include <vector>

#include "brdfa/renderer.h"
#include "storage/brdf_library.h"

namespace brdfa::server {

struct HotLoadProgress {
  bool enabled = false;
  bool done = false;
  int brdfs = 0;      // BRDFs to look at
  int visited = 0;    // BRDFs looked at so far
  int pipelines = 0;  // pipelines built from cached SPIR-V
  double ms = 0;      // wall time so far (total once done)
};

class HotLoader {
 public:
  HotLoader() = default;
  HotLoader(const HotLoader&) = delete;
  HotLoader& operator=(const HotLoader&) = delete;
  ~HotLoader() { stop(); }

  // Starts the background pass over `entries`; `renderer` must outlive stop().
  void start(std::shared_ptr<Renderer> renderer, std::vector<std::shared_ptr<const BrdfEntry>> entries);
  // Asks the pass to end after the BRDF in hand, and joins it. Idempotent.
  void stop();
  HotLoadProgress progress() const;

 private:
  std::thread thread_;
  std::atomic<bool> stop_{false}, enabled_{false}, done_{false};
  std::atomic<int> brdfs_{0}, visited_{0}, pipelines_{0};
  std::atomic<double> ms_{0};
};

}  // namespace brdfa::server
