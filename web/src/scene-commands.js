// Scene edits (docs/design.md section 4.6): the one module that turns what a panel wants changed
// into JSON merge patches (RFC 7386) of this tab's session scene, and the only caller of
// api.patchScene. An edit shows at once: it is applied to the local scene through set(). Per
// session at most one PATCH is in flight; edits made meanwhile are composed into the next one,
// so none is lost and none waits behind an older value. Every edit carries a sequence number;
// the answer to a PATCH is the server's scene as of the newest edit it carried, and the edits
// newer than that are applied on top of it before it is shown: a late answer never puts an
// old value back. An answer meant for another session than the tab's is dropped.
import * as api from './api.js';
import { state, set } from './state.js';

const isObject = (v) => v !== null && typeof v === 'object' && !Array.isArray(v);

/** RFC 7386: `target` with `patch` applied, as a new value; neither argument is modified. */
export function applyMergePatch(target, patch) {
  if (!isObject(patch)) return patch;
  const out = isObject(target) ? { ...target } : {};
  for (const [k, v] of Object.entries(patch)) {
    if (v === null) delete out[k];
    else out[k] = applyMergePatch(out[k], v);
  }
  return out;
}

/**
 * One merge patch doing what `older` then `newer` do, or null where none can: a merge patch
 * cannot say "replace this object whole", which a null or a plain value followed by an object
 * would need.
 */
export function composePatches(older, newer) {
  if (!isObject(older) || !isObject(newer)) return null;
  const out = { ...older };
  for (const [k, v] of Object.entries(newer)) {
    if (!isObject(v) || !(k in older)) { out[k] = v; continue; }
    if (!isObject(older[k])) return null;
    const inner = composePatches(older[k], v);
    if (inner === null) return null;
    out[k] = inner;
  }
  return out;
}

// Per session: {session, confirmed, queue, busy, seq, answered}.
//   confirmed: the server's scene as its latest answer gave it
//   queue:     [{patch | reload, local, seq, waiters}] not sent yet, oldest first
//   seq:       the newest edit's number; answered: the newest one the confirmed scene holds
const channels = new Map();

function channelOf(session) {
  let ch = channels.get(session);
  if (!ch) {
    ch = { session, confirmed: state.scene, queue: [], busy: false, seq: 0, answered: 0 };
    channels.set(session, ch);
  }
  return ch;
}

/** The local scene: the server's last answer with every edit it does not hold yet applied. */
const localScene = (ch) => ch.queue.reduce((s, e) => (e.patch && e.local ? applyMergePatch(s, e.patch) : s), ch.confirmed);

/** Shows the channel's local scene, unless the tab has moved on to another session. */
function show(ch) {
  if (state.session === ch.session) set({ scene: localScene(ch) });
}

function enqueue(ch, entry) {
  const last = ch.queue.at(-1);
  const merged = last?.patch && entry.patch && last.local === entry.local ? composePatches(last.patch, entry.patch) : null;
  if (merged) {
    last.patch = merged;
    last.seq = entry.seq;
    last.waiters.push(...entry.waiters);
  } else {
    ch.queue.push(entry);
  }
}

/** The server's scene after `entry`: its PATCH answered, or GET for a reload. */
const send = (ch, entry) => (entry.reload ? api.getScene(ch.session) : api.patchScene(ch.session, entry.patch));

/** After a PATCH failed the server kept its scene: ask for it (best effort). */
async function refetch(ch) {
  try { return await api.getScene(ch.session); } catch { return ch.confirmed; }
}

/** Sends the queue one request at a time until it is empty. */
async function pump(ch) {
  if (ch.busy) return;
  ch.busy = true;
  try {
    while (ch.queue.length) {
      const entry = ch.queue.shift();
      let answer, error;
      try { answer = await send(ch, entry); } catch (e) { error = e; }
      if (error && !entry.reload) answer = await refetch(ch);
      // Only a scene as new as the one shown replaces it: an older one is stale.
      if (answer && entry.seq > ch.answered) {
        ch.confirmed = answer;
        ch.answered = entry.seq;
        show(ch);
      }
      const scene = localScene(ch);
      for (const w of entry.waiters) {
        if (error) w.reject(error); else w.resolve(scene);
      }
    }
  } finally {
    ch.busy = false;
  }
}

function submit(ch, fields) {
  return new Promise((resolve, reject) => {
    enqueue(ch, { ...fields, seq: ++ch.seq, waiters: [{ resolve, reject }] });
    pump(ch);
  });
}

/**
 * Edits this tab's session scene. `change` is a merge patch, or a function that gets a copy of
 * the current local scene (free to modify) and returns one (null: no edit). The edit shows at
 * once unless `optimistic` is false (a reset whose result only the server knows). Resolves
 * with the local scene once the PATCH that carried it is answered; rejects with the error of
 * that PATCH (the local scene then returns to the server's).
 */
export function editScene(change, { optimistic = true } = {}) {
  if (!state.session || !state.scene) return Promise.reject(new Error('no session yet'));
  const patch = typeof change === 'function' ? change(structuredClone(state.scene)) : change;
  if (patch == null) return Promise.resolve(state.scene);
  const ch = channelOf(state.session);
  const done = submit(ch, { patch, local: optimistic });
  if (optimistic) set({ scene: applyMergePatch(state.scene, patch) });
  return done;
}

/**
 * Reads the server's scene again (after every edit sent before) and shows it with the edits
 * still waiting applied. Resolves with the local scene.
 */
export function reloadScene() {
  if (!state.session) return Promise.reject(new Error('no session yet'));
  return submit(channelOf(state.session), { reload: true, local: true });
}

/** True while an edit of the session's scene waits for its answer. */
export function editsPending(session = state.session) {
  const ch = channels.get(session);
  return !!ch && (ch.busy || ch.queue.length > 0);
}
