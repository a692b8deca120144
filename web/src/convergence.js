// Polls the session's error-against-time series (GET .../convergence) while the Convergence tab
// is shown and the session still renders. Not a panel: it only feeds state.convergence.
import * as api from './api.js';
import { state, set, on } from './state.js';

const PERIOD_MS = 1000;
const MAX_POINTS = 400;   // the server thins the answer evenly in log-time; the fit uses all

export function startConvergencePolling() {
  let timer = 0;
  let running = false;
  const wanted = () => state.visible && !!state.session && state.tab === 'tab-convergence';
  // Nothing new to fetch once rendering is done and the stats still show that moment.
  const stale = () => {
    const c = state.convergence;
    const s = state.stats;
    return !c || c.session !== state.session || !c.done || !s || c.scene_version !== s.scene_version || c.spp !== s.spp;
  };
  const poll = async () => {
    clearTimeout(timer);
    timer = 0;
    if (!wanted() || running) return;   // one loop: a poll in flight schedules the next
    if (stale()) {
      running = true;
      try {
        const session = state.session;
        const convergence = await api.getConvergence(session, MAX_POINTS);
        set({ convergence: { ...convergence, session } });
      } catch (e) {
        set({ status: `convergence: ${e.message}` });
      } finally {
        running = false;
      }
    }
    if (wanted() && !timer) timer = setTimeout(poll, PERIOD_MS);
  };
  on('tab', poll);
  on('visible', poll);
  on('session', poll);
  poll();
}
