// Side by side: B, a second session whose scene is this tab's with the selected object's BRDF
// and parameters replaced (another BRDF of the library, or the same one with other values),
// streamed beside the main view (A) under the same camera, environment and render settings:
// every scene change of A is mirrored into B (PUT, one at a time, the latest winning). Below,
// A - B (GET /api/sessions/{a}/difference?against={b}) on its diverging colour map with its
// colour bar and the relative RMS difference with its standard error, refreshed every 500 ms
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

export function mountCompare(el) {
  el.innerHTML = MARKUP;
  const $ = (c) => el.querySelector(c);
  const stateText = $('.sbs-state');
  const view = $('.sbs-b');
  const overlay = $('.sbs-view .overlay');
  const diff = $('.sbs-diff');
  let b = null;         // {id, index}: the open comparison
  let choice = null;    // {brdf, decls, params}: what B renders
  let lastSent = '';
  let timer = 0;
  let nonce = 0;
  let diffUrl = '';
  let seen = '';        // the samples (A, B) of the difference on screen

  const object = () => state.scene?.objects?.[b ? b.index : state.selected];
  /** A's scene with its object's BRDF and values replaced by B's choice. */
  const mirror = () => {
    const scene = structuredClone(state.scene);
    delete scene.notes;   // the server works notes out again
    const o = scene.objects[b ? b.index : state.selected];
    if (o) Object.assign(o, { brdf: choice.brdf, params: choice.params });
    return scene;
  };
  const send = coalesce(async (scene) => {
    const text = JSON.stringify(scene);
    if (!b || text === lastSent) return;
    try {
      await api.putScene(b.id, scene);
      lastSent = text;
      stateText.textContent = '';
    } catch (e) {
      stateText.textContent = `B: ${e.message}`;
    }
  });
  const mirrorNow = () => { if (b && choice) send(mirror()); };

  // ---- what B renders: a BRDF of the library and its values ----
  function choose(name) {
    const decls = state.library.find((x) => x.name === name)?.params || [];
    const o = object();
    // The same BRDF starts from A's values (then differs by a slider), another from its defaults.
    const params = o?.brdf === name ? { ...defaults(decls), ...o.params } : defaults(decls);
    choice = { brdf: name, decls, params };
    paramControls($('.sbs-params'), decls, params, (values) => { choice.params = values; mirrorNow(); });
    $('.sbs-name').textContent = name;
    mirrorNow();
  }
  $('.sbs-brdf').addEventListener('change', (ev) => choose(ev.target.value));
  on('library', ({ library }) => {
    const sel = $('.sbs-brdf');
    const keep = choice?.brdf || object()?.brdf;
    sel.replaceChildren(...library.filter((x) => !x.broken).map((x) => {
      const o = document.createElement('option');
      o.value = o.textContent = x.name;
      return o;
    }));
    if (keep && library.some((x) => x.name === keep)) sel.value = keep;
    if (!choice && sel.value) choose(sel.value);
  });
  on('scene', mirrorNow);

  // ---- B's stream, its stats and the difference: while the tab is shown ----
  // Elsewhere B's stream closes and it stops rendering (unwatched), leaving the CPU to A.
  const watching = () => b?.id && state.visible && !el.closest('.tab-page')?.hidden;
  const connect = () => {
    if (watching()) view.src = api.streamUrl(b.id, nonce++);
  };
  view.addEventListener('error', () => { if (watching()) setTimeout(connect, 1000); });

  function showBar(range) {
    const canvas = $('.sbs-bar');
    const g = prepare(canvas, widthOf(canvas, 120), 34);
    const ticks = [{ pos: 0, label: `−${sig(range)} (B brighter)` }, { pos: 0.5, label: '0' }, { pos: 1, label: `+${sig(range)} (A brighter)` }];
    drawColourBar(g, { x: 1, y: 2, w: widthOf(canvas, 120) - 2, h: 12 }, (p) => diverging(2 * p - 1), ticks, false);
  }

  let polling = false;   // one loop: a poll in flight schedules the next
  async function poll() {
    clearTimeout(timer);
    if (!watching() || polling) return;
    const id = b.id;
    polling = true;
    try {
      const s = await api.getStats(id);
      overlay.textContent = `${s.spp} spp · err ${errPct(s.rel_error)}${s.done ? ' · done' : ''}`;
      // A new difference while either view gains samples (or after a restart), once more at
      // the end; not before both have an error estimate (the server answers 400 until then).
      const key = `${state.stats?.spp}/${s.spp}`;
      if (key !== seen && s.rel_error != null && state.stats?.rel_error != null) {
        const d = await api.getDifference(state.session, id);
        if (b?.id !== id) return;
        seen = key;
        if (diffUrl) URL.revokeObjectURL(diffUrl);
        diffUrl = URL.createObjectURL(d.image);
        diff.src = diffUrl;
        showBar(d.range);
        $('.sbs-rms').textContent = `relative RMS difference ${errPct(d.relRms)} ± ${errPct(d.relRmsError)} ` +
          `(A ${d.samples[0]} spp, B ${d.samples[1]} spp)`;
      }
    } catch (e) {
      // 400 until both views have an error estimate: the first passes.
      $('.sbs-rms').textContent = e.status === 400 ? 'waiting for samples…' : `difference: ${e.message}`;
    } finally {
      polling = false;
    }
    if (b?.id === id) timer = setTimeout(poll, PERIOD_MS);
  }
  const watch = () => {
    if (watching()) { connect(); poll(); return; }
    clearTimeout(timer);
    view.removeAttribute('src');
  };
  on('visible', watch);
  on('tab', watch);

  // ---- open and close ----
  $('.sbs-open').addEventListener('click', async () => {
    if (b || !choice || !state.scene) return;
    stateText.textContent = 'starting B…';
    $('.sbs-open').disabled = true;
    try {
      // The server's scene, not only what this page last heard: a script may have changed it.
      await reloadScene();
      const index = state.selected;
      b = { id: null, index };
      const scene = mirror();
      // Beside A: behind several replicas the difference needs both sessions on one server.
      const created = await api.createSession(scene, state.session);
      b.id = created.id;
      lastSent = JSON.stringify(scene);
      el.dataset.session = created.id;
      stateText.textContent = `B is session ${created.id} (object ${index + 1} replaced)`;
      $('.sbs-close').hidden = false;
      $('.sbs-open').hidden = true;
      watch();
      mirrorNow();   // a change of A while B was being made
    } catch (e) {
      b = null;
      stateText.textContent = `compare: ${e.message}`;
    } finally {
      $('.sbs-open').disabled = false;
    }
  });

  async function close() {
    if (!b?.id) return;
    const id = b.id;
    b = null;
    clearTimeout(timer);
    view.removeAttribute('src');
    diff.removeAttribute('src');
    overlay.textContent = '';
    $('.sbs-rms').textContent = '';
    delete el.dataset.session;
    seen = '';
    lastSent = '';
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
  window.addEventListener('pagehide', () => { if (b?.id) api.deleteSession(b.id, { keepalive: true }); });
}
