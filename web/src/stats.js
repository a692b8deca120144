// Polls the session's stats (which also counts as watching, keeping the render thread busy) and
// the server's health once. Not a panel: it only feeds state.stats and state.health.
import * as api from './api.js';
import { state, set } from './state.js';

const PERIOD_MS = 500;   // the overlay's numbers should feel live, and stats never wait for the device

export function startStatsPolling() {
  api.health().then((health) => set({ health })).catch((e) => set({ status: `health: ${e.message}` }));
  let timer = 0;
  const poll = async () => {
    try {
      if (state.session) set({ stats: await api.getStats(state.session) });
    } catch (e) {
      set({ status: `stats: ${e.message}` });
    }
    timer = setTimeout(poll, PERIOD_MS);
  };
  poll();
  return () => clearTimeout(timer);
}
