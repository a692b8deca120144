// Entry point (bundled by build.mjs into dist/main.js): mounts the panels, then finds this tab's
// session and loads the BRDF its first object uses. Panels only meet through state.js.
// The editor (CodeMirror, 430 KB) is a dynamic import started once the first frame is on screen
// (or after 1.5 s): on a small machine, parsing it would compete with the first pass for the CPU.
import { state, set, on } from './state.js';
import { startSession, mountSessionPanel } from './panels/session.js';
import { mountViewer } from './panels/viewer.js';
import { mountCamera } from './panels/camera.js';
import { mountViewSize } from './panels/view-size.js';
import { mountLog } from './panels/log.js';
import { mountParams } from './panels/params.js';
import { startStatsPolling } from './stats.js';
import { startConvergencePolling } from './convergence.js';
import { mountConvergence } from './panels/convergence.js';
import { mountTabs } from './panels/tabs.js';
import { mountTests } from './panels/tests.js';
import { mountFrameSaver } from './panels/frame-saver.js';
import { mountObjects } from './panels/objects.js';
import { mountEnvironment } from './panels/environment.js';
import { mountAnalysis } from './panels/analysis.js';
import { mountCompare } from './panels/compare.js';
import { refreshLibrary, refreshAssets } from './library.js';

const $ = (id) => document.getElementById(id);
const visibility = () => set({ visible: document.visibilityState === 'visible' });
document.addEventListener('visibilitychange', visibility);
visibility();

mountSessionPanel($('session'));
mountViewer($('viewer'));
mountCamera($('viewer'), $('camera'), document.querySelector('.view-bar'));
mountViewSize($('view'), document.querySelector('main .left'));
mountLog($('log'));
mountParams($('params'));
mountTabs(document.querySelector('.tabs'));
mountTests($('tests'));
mountFrameSaver($('frame-saver'));
mountObjects($('objects'));
mountEnvironment($('environment'));
mountConvergence($('convergence'));
mountAnalysis($('analysis'));
mountCompare($('compare'));
const firstFrame = new Promise((resolve) => { on('firstFrame', resolve); setTimeout(resolve, 1500); });
const editor = firstFrame.then(() => import('./panels/editor.js')).then((m) => m.mountEditor($('editor'), $('library')));

(async () => {
  try {
    await startSession();
    startStatsPolling();
    startConvergencePolling();
    const name = state.scene.objects?.[0]?.brdf;
    if (!name) { set({ status: 'the scene has no object' }); return; }
    refreshLibrary();
    refreshAssets();
    await (await editor).openInitial(name);
  } catch (e) {
    set({ status: `start failed: ${e.message}` });
  }
})();
