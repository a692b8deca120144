// Viewer: the session's live PNG stream in an <img> (multipart/x-mixed-replace), with spp,
// elapsed time, relative error and frames per second overlaid.
import * as api from '../api.js';
import { state, set, on } from '../state.js';
import { errPct, fixed, seconds } from '../format.js';

export function mountViewer(el) {
  const img = el.querySelector('img');
  const overlay = el.querySelector('.overlay');
  let nonce = 0;
  let retry = 0;
  let live = false;
  const connect = () => {
    clearTimeout(retry);
    live = !!state.session && state.visible;
    if (live) img.src = api.streamUrl(state.session, nonce++);
  };
  // A dropped stream (server restart, network) reconnects after a pause.
  img.addEventListener('error', () => { if (live) retry = setTimeout(connect, 1000); });
  // An <img> fires `load` once, for the first part of a multipart stream.
  img.addEventListener('load', () => { if (!state.firstFrame) set({ firstFrame: true }); });
  img.draggable = false;   // left-drag looks around (camera panel), never drags the image
  on('session', connect);
  // A hidden tab closes its stream, so a background tab does not keep its session rendering
  // (the last frame stays on screen); showing the tab again reconnects.
  on('visible', ({ visible }) => {
    if (visible) { connect(); return; }
    live = false;
    clearTimeout(retry);
    if (img.naturalWidth) {   // keep the last frame: a still copy replaces the live stream
      const c = document.createElement('canvas');
      c.width = img.naturalWidth;
      c.height = img.naturalHeight;
      c.getContext('2d').drawImage(img, 0, 0);
      img.src = c.toDataURL();
    } else {
      img.removeAttribute('src');
    }
    overlay.textContent = 'paused (tab hidden)';
  });

  on('stats', ({ stats }) => {
    // A stats reply that was in flight when the tab was hidden must not cover 'paused'.
    if (!stats || !state.visible) return;
    // converged: rel_error reached render.target_error; max spp: render.max_samples reached.
    const end = stats.converged ? ' · converged' : stats.max_samples_reached ? ' · max spp' : '';
    const target = stats.target_error != null ? ` (target ${errPct(stats.target_error)})` : '';
    overlay.textContent = `${stats.spp} spp · ${seconds(stats.elapsed_ms)} · err ${errPct(stats.rel_error)}${target} · ` +
      `${fixed(stats.fps)} fps${end}`;
  });
}
