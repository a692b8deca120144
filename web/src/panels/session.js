// Sessions: each tab works in its own session, never `default`, so one student's edits never
// show in another's view. The id lives in the URL (?session=<id>): a reload keeps the state; a
// new tab without it creates a fresh session.
import * as api from '../api.js';
import { set, on } from '../state.js';

// What a fresh tab shows: the default session's look (docs/api.md, Sessions), not the
// all-defaults furnace scene, where a white sphere is invisible against a white background.
const STARTER_SCENE = {
  environment: { name: 'sky', visible: true },
  objects: [{ mesh: 'sphere', brdf: 'ggx' }],
  render: { width: 512, height: 512, samples_per_frame: 4, max_samples: 4096 },
};

/** Finds or creates this tab's session; sets state.session and state.scene. */
export async function startSession() {
  const url = new URL(location.href);
  const wanted = url.searchParams.get('session');
  if (wanted && wanted !== 'default') {
    try {
      const s = await api.getSession(wanted);
      set({ session: s.id, scene: s.scene });
      return;
    } catch (e) {
      // 404: the server restarted or dropped it; start over in a new session below.
      if (e.status !== 404) throw e;
      set({ status: `session ${wanted} is gone; started a new one` });
    }
  }
  const created = await api.createSession(STARTER_SCENE);
  url.searchParams.set('session', created.id);
  history.replaceState(null, '', url);
  set({ session: created.id, scene: created.scene });
}

export function mountSessionPanel(el) {
  const id = el.querySelector('.session-id');
  const fresh = el.querySelector('.session-new');
  on('session', ({ session }) => {
    id.textContent = session;
    // "New session": the same page without ?session= creates one.
    const u = new URL(location.href);
    u.searchParams.delete('session');
    fresh.href = u.pathname + u.search;
  });
}
