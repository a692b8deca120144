// Renderer::create (renderer.h): the renderer in this process, or, with RendererOptions::isolate,
// one whose device lives in a supervised worker process (remote_renderer.h).
#include <memory>
#include <utility>

#include "brdfa/renderer.h"

#include "isolation/remote_renderer.h"
#include "render/local_renderer.h"

namespace brdfa {

Result<std::shared_ptr<Renderer>> Renderer::create(const RendererOptions& options) {
  if (options.isolate) return createRemoteRenderer(options);
  auto r = LocalRenderer::create(options);
  if (!r) return r.takeError();
  return std::shared_ptr<Renderer>(std::move(r.value()));
}

}  // namespace brdfa
