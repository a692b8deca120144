// Side by side: B, a second session whose scene is this tab's with the selected object's BRDF
// and parameters replaced (another BRDF of the library, or the same one with other values),
// streamed beside the main view (A) under the same camera, environment and render settings:
// every scene change of A is mirrored into B (PUT, one at a time, the latest winning). Below,
// A - B (GET /api/sessions/{a}/difference?against={b}) on its diverging colour map with its
// colour bar and the relative RMS difference with its standard error, refreshed every PERIOD_MS
// while either view gains samples. Closing deletes B; so does leaving the page.
import * as api from '../api.js';
import { state, on } from '../state.js';
import { coalesce } from '../coalesce.js';
import { reloadScene } from '../scene-commands.js';
import { paramControls, defaults } from '../param-controls.js';
import { prepare, widthOf } from '../analysis-plots/canvas.js';
import { drawColourBar } from '../analysis-plots/heatmap.js';
import { diverging } from '../analysis-plots/colormap.js';
import { errPct, sig } from '../format.js';

const PERIOD_MS = 500;

// Constant markup, parsed once: no value is ever interpolated into it (names go in as text).
const MARKUP = `
  <div class="row">
    <label title="what B renders in place of the selected object's BRDF">B: BRDF <select class="sbs-brdf"></select></label>
    <button type="button" class="sbs-open" title="a second session, under this view's camera and environment">Compare</button>
    <button type="button" class="sbs-close" hidden>Close</button>
    <span class="sbs-state hint" role="status"></span>
  </div>
  <div class="sbs-params params-list"></div>
  <div class="sbs-panes">
    <figure><figcaption>B <span class="sbs-name hint"></span></figcaption>
      <div class="sbs-view"><img class="sbs-b" alt="live render of B"><div class="overlay"></div></div></figure>
    <figure><figcaption>A − B (luminance)</figcaption>
      <img class="sbs-diff" alt="difference of A and B on a diverging colour map"><canvas class="sbs-bar"></canvas>
      <div class="sbs-rms" title="relative RMS difference over A's object, both images' noise taken out, ± its standard error"></div></figure>
  </div>`;

/** The colour bar of the difference: -range (B brighter) to +range (A brighter). */
function showBar(canvas, range) {
  const g = prepare(canvas, widthOf(canvas, 120), 34);
  const ticks = [{ pos: 0, label: `−${sig(range)} (B brighter)` }, { pos: 0.5, label: '0' }, { pos: 1, label: `+${sig(range)} (A brighter)` }];
  drawColourBar(g, { x: 1, y: 2, w: widthOf(canvas, 120) - 2, h: 12 }, (p) => diverging(2 * p - 1), ticks, false);
}

/** What B renders: a BRDF of the library and its values; A's scene is mirrored into B. */
function mountChoice(c) {
  const { $ } = c;
  const object = () => state.scene?.objects?.[c.b ? c.b.index : state.selected];
  function choose(name) {
    const decls = state.library.find((x) => x.name === name)?.params || [];
    const o = object();
    // The same BRDF starts from A's values (then differs by a slider), another from its defaults.
    const params = o?.brdf === name ? { ...defaults(decls), ...o.params } : defaults(decls);
    c.choice = { brdf: name, decls, params };
    paramControls($('.sbs-params'), decls, params, (values) => { c.choice.params = values; c.mirrorNow(); });
    $('.sbs-name').textContent = name;
    c.mirrorNow();
  }
  $('.sbs-brdf').addEventListener('change', (ev) => choose(ev.target.value));
  on('library', ({ library }) => {
    const sel = $('.sbs-brdf');
    const keep = c.choice?.brdf || object()?.brdf;
    sel.replaceChildren(...library.filter((x) => !x.broken).map((x) => {
      const o = document.createElement('option');
      o.value = o.textContent = x.name;
      return o;
    }));
    if (keep && library.some((x) => x.name === keep)) sel.value = keep;
    if (!c.choice && sel.value) choose(sel.value);
  });
  on('scene', c.mirrorNow);
}

/** B's stream, its stats and the difference, while the tab is shown. Returns watch(). */
function mountWatch(el, c) {
  const { $, view } = c;
  const overlay = $('.sbs-view .overlay');
  let nonce = 0;
  let diffUrl = '';
  // Elsewhere B's stream closes and it stops rendering (unwatched), leaving the CPU to A.
  const watching = () => c.b?.id && state.visible && !el.closest('.tab-page')?.hidden;
  const connect = () => {
    if (watching()) view.src = api.streamUrl(c.b.id, nonce++);
  };
  view.addEventListener('error', () => { if (watching()) setTimeout(connect, 1000); });

  /** A new difference while either view gains samples (or after a restart), once more at the
   *  end; not before both have an error estimate (the server answers 400 until then). */
  async function showDifference(id, s) {
    const key = `${state.stats?.spp}/${s.spp}`;
    if (key === c.seen || s.rel_error == null || state.stats?.rel_error == null) return;
    const d = await api.getDifference(state.session, id);
    if (c.b?.id !== id) return;
    c.seen = key;
    if (diffUrl) URL.revokeObjectURL(diffUrl);
    diffUrl = URL.createObjectURL(d.image);
    c.diff.src = diffUrl;
    showBar($('.sbs-bar'), d.range);
    $('.sbs-rms').textContent = `relative RMS difference ${errPct(d.relRms)} ± ${errPct(d.relRmsError)} ` +
      `(A ${d.samples[0]} spp, B ${d.samples[1]} spp)`;
  }
  let polling = false;   // one loop: a poll in flight schedules the next
  async function poll() {
    clearTimeout(c.timer);
    if (!watching() || polling) return;
    const id = c.b.id;
    polling = true;
    try {
      const s = await api.getStats(id);
      overlay.textContent = `${s.spp} spp · err ${errPct(s.rel_error)}${s.done ? ' · done' : ''}`;
      await showDifference(id, s);
    } catch (e) {
      // 400 until both views have an error estimate: the first passes.
      $('.sbs-rms').textContent = e.status === 400 ? 'waiting for samples…' : `difference: ${e.message}`;
    } finally {
      polling = false;
    }
    if (c.b?.id === id) c.timer = setTimeout(poll, PERIOD_MS);
  }
  const watch = () => {
    if (watching()) { connect(); poll(); return; }
    clearTimeout(c.timer);
    view.removeAttribute('src');
  };
  on('visible', watch);
  on('tab', watch);
  return watch;
}

/** Compare opens B beside A; Close (or leaving the page) deletes it. */
function mountOpenClose(el, c, watch) {
  const { $, stateText } = c;
  $('.sbs-open').addEventListener('click', async () => {
    if (c.b || !c.choice || !state.scene) return;
    stateText.textContent = 'starting B…';
    $('.sbs-open').disabled = true;
    try {
      // The server's scene, not only what this page last heard: a script may have changed it.
      await reloadScene();
      const index = state.selected;
      c.b = { id: null, index };
      const scene = c.mirror();
      // Beside A: behind several replicas the difference needs both sessions on one server.
      const created = await api.createSession(scene, state.session);
      c.b.id = created.id;
      c.lastSent = JSON.stringify(scene);
      el.dataset.session = created.id;
      stateText.textContent = `B is session ${created.id} (object ${index + 1} replaced)`;
      $('.sbs-close').hidden = false;
      $('.sbs-open').hidden = true;
      watch();
      c.mirrorNow();   // a change of A while B was being made
    } catch (e) {
      c.b = null;
      stateText.textContent = `compare: ${e.message}`;
    } finally {
      $('.sbs-open').disabled = false;
    }
  });

  async function close() {
    if (!c.b?.id) return;
    const id = c.b.id;
    c.b = null;
    clearTimeout(c.timer);
    c.view.removeAttribute('src');
    c.diff.removeAttribute('src');
    $('.sbs-view .overlay').textContent = '';
    $('.sbs-rms').textContent = '';
    delete el.dataset.session;
    c.seen = '';
    c.lastSent = '';
    $('.sbs-close').hidden = true;
    $('.sbs-open').hidden = false;
    try {
      await api.deleteSession(id);
      stateText.textContent = 'closed';
    } catch (e) {
      stateText.textContent = `close: ${e.message}`;
    }
  }
  $('.sbs-close').addEventListener('click', close);
  // Leaving the page: a DELETE that outlives it (sendBeacon can only POST).
  window.addEventListener('pagehide', () => { if (c.b?.id) api.deleteSession(c.b.id, { keepalive: true }); });
}

export function mountCompare(el) {
  el.innerHTML = MARKUP;
  const $ = (q) => el.querySelector(q);
  // What the sub-views share.
  const c = {
    $,
    stateText: $('.sbs-state'),
    view: $('.sbs-b'),
    diff: $('.sbs-diff'),
    b: null,         // {id, index}: the open comparison
    choice: null,    // {brdf, decls, params}: what B renders
    lastSent: '',
    timer: 0,
    seen: '',        // the samples (A, B) of the difference on screen
  };
  /** A's scene with its object's BRDF and values replaced by B's choice. */
  c.mirror = () => {
    const scene = structuredClone(state.scene);
    delete scene.notes;   // the server works notes out again
    const o = scene.objects[c.b ? c.b.index : state.selected];
    if (o) Object.assign(o, { brdf: c.choice.brdf, params: c.choice.params });
    return scene;
  };
  const send = coalesce(async (scene) => {
    const text = JSON.stringify(scene);
    if (!c.b || text === c.lastSent) return;
    try {
      await api.putScene(c.b.id, scene);
      c.lastSent = text;
      c.stateText.textContent = '';
    } catch (e) {
      c.stateText.textContent = `B: ${e.message}`;
    }
  });
  c.mirrorNow = () => { if (c.b && c.choice) send(c.mirror()); };

  mountChoice(c);
  const watch = mountWatch(el, c);
  mountOpenClose(el, c, watch);
}
