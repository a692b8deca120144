// Polls the session's stats (which also counts as watching, keeping the render thread busy) and
// the server's health once. Not a panel: it only feeds state.stats and state.health.
import * as api from './api.js';
import { state, set, on } from './state.js';

const PERIOD_MS = 500;   // the overlay's numbers should feel live, and stats never wait for the device

export function startStatsPolling() {
  api.health().then((health) => set({ health })).catch((e) => set({ status: `health: ${e.message}` }));
  let timer = 0;
  let running = false;
  // A stats request counts as watching (it keeps the session rendering): a hidden tab stops
  // polling, and polls again at once when it is shown.
  const poll = async () => {
    clearTimeout(timer);
    timer = 0;
    if (!state.visible || running) return;   // one loop: a poll in flight schedules the next
    running = true;
    try {
      if (state.session) set({ stats: await api.getStats(state.session) });
    } catch (e) {
      set({ status: `stats: ${e.message}` });
    } finally {
      running = false;
    }
    if (state.visible && !timer) timer = setTimeout(poll, PERIOD_MS);
  };
  on('visible', ({ visible }) => { if (visible) poll(); else { clearTimeout(timer); timer = 0; } });
  poll();
  return () => clearTimeout(timer);
}
