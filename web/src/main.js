// Entry point (bundled by build.mjs into dist/main.js): mounts the panels, then finds this tab's
// session and loads the BRDF its first object uses. Panels only meet through state.js.
// The editor (CodeMirror) is a dynamic import: the session and its stream start without
// waiting for it, so the first frame is on screen sooner.
import * as api from './api.js';
import { state, set } from './state.js';
import { startSession, mountSessionPanel } from './panels/session.js';
import { mountViewer } from './panels/viewer.js';
import { mountCamera } from './panels/camera.js';
import { mountLog } from './panels/log.js';
import { mountParams } from './panels/params.js';
import { startStatsPolling } from './stats.js';

const $ = (id) => document.getElementById(id);

mountSessionPanel($('session'));
mountViewer($('viewer'));
mountCamera($('viewer'), $('camera'));
mountLog($('log'));
mountParams($('params'));
const editor = import('./panels/editor.js').then((m) => m.mountEditor($('editor')));

(async () => {
  try {
    await startSession();
    startStatsPolling();
    const name = state.scene.objects?.[0]?.brdf;
    if (!name) { set({ status: 'the scene has no object' }); return; }
    const brdf = await api.getBrdf(name);
    (await editor).load(brdf.source);
    set({ brdf: { name: brdf.name, params: brdf.params },
          status: brdf.builtin ? `editing a copy of built-in "${brdf.name}"` : `editing "${brdf.name}"` });
  } catch (e) {
    set({ status: `start failed: ${e.message}` });
  }
})();
