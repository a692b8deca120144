// Class (the teacher, with identities on): every session on the server (GET /api/sessions lists
// them all for the teacher, with owner, owner_display_name and view_key), each with a thumbnail
// of its latest frame reloaded every couple of seconds; clicking one watches its live stream
// full size. Images go through the session's view key (an <img> sends no token). Owners'
// display names are shown as text. Polls only while the tab is shown and the page visible.
import * as api from '../api.js';
import { state, on } from '../state.js';

const PERIOD_MS = 2000;

const make = (tag, className, text) => {
  const e = document.createElement(tag);
  if (className) e.className = className;
  if (text !== undefined) e.textContent = text;
  return e;
};

/** Adds the Class tab's button to `nav` and its page to the tab pages; call before mountTabs. */
export function addClassTab(nav, before) {
  const button = make('button', '', 'Class');
  Object.assign(button, { type: 'button', title: 'every session of the class, live' });
  button.setAttribute('role', 'tab');
  button.dataset.tab = 'tab-class';
  nav.insertBefore(button, nav.querySelector(`[data-tab="${before}"]`));
  nav.classList.add('wrap');   // one tab more than the column is wide for: a second row
  const page = make('div', 'tab-page panel');
  page.id = 'tab-class';
  page.setAttribute('role', 'tabpanel');
  page.hidden = true;
  const el = make('div');
  el.id = 'class';
  page.append(el);
  document.getElementById(before).before(page);
  return el;
}

/** The tab's fixed elements: a head with a status line, the watched view, the list. */
function buildPage(el) {
  const head = make('div', 'row');
  const status = make('span', 'class-status hint');
  status.setAttribute('role', 'status');
  head.append(make('strong', '', 'Sessions of the class'), status);
  const watch = make('div', 'class-watch');
  watch.hidden = true;
  const figure = make('figure');
  const caption = make('figcaption');
  const watchName = make('span', 'class-watch-name');
  const close = make('button', 'class-watch-close', 'close');
  close.type = 'button';
  caption.append(watchName, ' ', close);
  const big = make('img', 'class-watch-img');
  big.alt = 'live render of the watched session';
  big.draggable = false;
  figure.append(caption, big);
  watch.append(figure);
  const list = make('ul', 'class-list');
  list.setAttribute('aria-label', 'sessions');
  el.append(head, watch, list);
  return { status, watch, watchName, close, big, list };
}

export function mountClass(el) {
  const { status, watch, watchName, close, big, list } = buildPage(el);
  const items = new Map();   // session id -> {li, img, owner, loading}
  let watched = null;        // the session shown full size
  let nonce = 0;
  let timer = 0;
  let running = false;
  const shown = () => state.visible && state.tab === 'tab-class';

  const thumb = () => {
    const img = make('img', 'class-thumb');
    img.draggable = false;
    return img;
  };
  const ownerOf = (s) => s.owner_display_name || s.owner || (s.id === 'default' ? 'default (shared)' : '(no owner)');

  function item(s) {
    let it = items.get(s.id);
    if (!it) {
      const li = make('li', 'class-item');
      li.dataset.session = s.id;
      const pick = make('button', 'class-pick');
      pick.type = 'button';
      const img = thumb();
      const owner = make('span', 'class-owner');
      const id = make('span', 'class-id hint', s.id === state.session ? `${s.id} (this tab)` : s.id);
      pick.append(img, owner, id);
      li.append(pick);
      it = { li, img, owner, loading: false };
      pick.addEventListener('click', () => watchSession(s.id));
      items.set(s.id, it);
    }
    it.session = s;
    it.owner.textContent = ownerOf(s);
    it.owner.title = s.owner ? `user ${s.owner}` : '';
    it.img.alt = `latest frame of ${ownerOf(s)}'s session ${s.id}`;
    it.li.classList.toggle('watched', s.id === watched);
    return it;
  }

  function watchSession(id) {
    watched = id;
    const it = items.get(id);
    watchName.textContent = it ? `${ownerOf(it.session)} · ${id}` : id;
    watch.dataset.session = id;
    watch.hidden = false;
    for (const [k, x] of items) x.li.classList.toggle('watched', k === id);
    connect();
  }
  const connect = () => {
    if (watched && shown()) big.src = api.streamUrl(watched, nonce++);
    else big.removeAttribute('src');
  };
  big.addEventListener('error', () => { if (watched && shown()) setTimeout(connect, 1000); });
  close.addEventListener('click', () => {
    watched = null;
    watch.hidden = true;
    delete watch.dataset.session;
    big.removeAttribute('src');
    for (const x of items.values()) x.li.classList.remove('watched');
  });

  async function poll() {
    clearTimeout(timer);
    timer = 0;
    if (!shown() || running) return;   // one loop: a poll in flight schedules the next
    running = true;
    try {
      const sessions = await api.listSessions();
      const ids = new Set(sessions.map((s) => s.id));
      for (const id of [...items.keys()]) if (!ids.has(id)) items.delete(id);
      list.replaceChildren(...sessions.map((s) => item(s).li));
      for (const it of items.values()) {
        // A thumbnail still loading keeps its request: a slow server gets one at a time.
        if (it.loading) continue;
        it.loading = true;
        // Loaded beside the one shown, which it replaces once whole: no blank while loading.
        const next = thumb();
        next.alt = it.img.alt;
        next.addEventListener('load', () => { it.img.replaceWith(next); it.img = next; it.loading = false; });
        next.addEventListener('error', () => { it.loading = false; });
        next.src = api.frameUrl(it.session.id, nonce++);
      }
      if (watched && !ids.has(watched)) watchName.textContent = `${watched}: the session has ended`;
      status.textContent = `${sessions.length} session${sessions.length === 1 ? '' : 's'}`;
    } catch (e) {
      status.textContent = `sessions: ${e.message}`;
    } finally {
      running = false;
    }
    if (shown() && !timer) timer = setTimeout(poll, PERIOD_MS);
  }
  const update = () => {
    connect();
    if (shown()) poll();
    else { clearTimeout(timer); timer = 0; }
  };
  on('tab', update);
  on('visible', update);
  on('session', update);
}
