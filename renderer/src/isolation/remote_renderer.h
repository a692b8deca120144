// The isolated renderer (RendererOptions::isolate): a Renderer whose device lives in
// a brdfa-render-worker process under a watchdog.
//  - The worker reports the request whose pipeline build or queue submission overran its
//    budget, or that was in flight when its memory passed the limit (device_activity.h); the
//    watchdog here also stops a worker that stops answering. Either way the worker is killed and
//    a new one started.
//  - The overrunning request fails with RenderBudget naming the BRDF and the budget, and its
//    programs are quarantined: every later request using them fails the same way, without
//    reaching the device. Programs proven by an earlier build (or pass) within budget are not
//    blamed for a later overrun of that kind; the scene is (too large an image, too many
//    samples per frame).
//  - Every other request in flight is sent again to the new worker, after its view has been
//    restored there from the view's last scene (accumulation restarts). A view whose pass
//    overran is not restored: its calls fail with the error until it gets a new scene.
#pragma once

#include <memory>

#include "brdfa/renderer.h"

namespace brdfa {

// Starts the worker and opens its device; fails as Renderer::create would.
Result<std::shared_ptr<Renderer>> createRemoteRenderer(const RendererOptions& options);

}  // namespace brdfa
