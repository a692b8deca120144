// Viewer: the session's live PNG stream in an <img> (multipart/x-mixed-replace), with spp,
// elapsed time, relative error and frames per second overlaid.
import * as api from '../api.js';
import { state, on } from '../state.js';
import { pct, fixed, seconds } from '../format.js';

export function mountViewer(el) {
  const img = el.querySelector('img');
  const overlay = el.querySelector('.overlay');
  let nonce = 0;
  let retry = 0;
  const connect = () => {
    clearTimeout(retry);
    if (state.session) img.src = api.streamUrl(state.session, nonce++);
  };
  // A dropped stream (server restart, network) reconnects after a pause.
  img.addEventListener('error', () => { retry = setTimeout(connect, 1000); });
  img.draggable = false;   // left-drag looks around (camera panel), never drags the image
  on('session', connect);

  on('stats', ({ stats }) => {
    if (!stats) return;
    overlay.textContent = `${stats.spp} spp · ${seconds(stats.elapsed_ms)} · err ${pct(stats.rel_error)} · ` +
      `${fixed(stats.fps)} fps${stats.converged ? ' · converged' : ''}`;
  });
}
