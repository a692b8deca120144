// Frame saver: links that download the session's current frame as PNG (tone-mapped, what the
// view shows) or as linear float radiance (PFM, EXR). The server names the file
// <session>-<spp>spp.<ext> (Content-Disposition: attachment).
import * as api from '../api.js';
import { on } from '../state.js';

export function mountFrameSaver(el) {
  on('session', ({ session }) => {
    for (const f of ['png', 'pfm', 'exr']) el.querySelector(`.save-${f}`).href = api.frameDownloadUrl(session, f);
  });
}
