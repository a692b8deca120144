// Entry point (bundled by build.mjs into dist/main.js): finds out who this page is (panels/auth.js:
// the join or token screen until it knows), mounts the panels, then finds this tab's session and
// loads the BRDF its first object uses. Panels only meet through state.js.
// The editor (CodeMirror, the largest part of the bundle) is a dynamic import started once the
// first frame is on screen (or after a short wait at most): on a small machine, parsing it would
// compete with the first pass for the CPU.
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
import { authenticate, mountWhoAmI } from './panels/auth.js';
import { addClassTab, mountClass } from './panels/class.js';
import * as api from './api.js';

const $ = (id) => document.getElementById(id);
// `visible`: the view can be seen. Not while the token screen covers the page: streams and
// polls stop then.
let covered = false;
const visibility = () => set({ visible: document.visibilityState === 'visible' && !covered });
document.addEventListener('visibilitychange', visibility);
visibility();

function start(me) {
  set({ me });
  mountWhoAmI($('whoami'), me);
  // A token revoked while the page is open: the token screen again, then a fresh start.
  let asked = false;
  api.onUnauthorized(() => {
    if (asked) return;
    asked = true;
    covered = true;
    visibility();
    authenticate($('auth'), { reason: 'This browser\'s token is no longer accepted (revoked, or the user was removed).' })
      .then(() => location.reload());
  });
  mountSessionPanel($('session'));
  mountViewer($('viewer'));
  mountCamera($('viewer'), $('camera'), document.querySelector('.view-bar'));
  mountViewSize($('view'), document.querySelector('main .left'));
  mountLog($('log'));
  mountParams($('params'));
  // The teacher's view of every session; in none mode (one person) the page stays as it was.
  if (me.role === 'teacher' && me.mode !== 'none') mountClass(addClassTab(document.querySelector('.tabs'), 'tab-help'));
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
}

authenticate($('auth')).then(start, (e) => {
  // The server did not answer who this is (down, or an error): say so where the view would be.
  document.querySelector('#viewer .overlay').textContent = `start failed: ${e.message}`;
});
