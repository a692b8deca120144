// Objects (the object editor): add and remove objects (at least one stays), choose or upload a
// mesh and up to four textures, choose the BRDF, translate/rotate/scale; and the scene-wide
// samples per frame, maximum samples, sampling mode and target error. Every change edits the
// whole `objects` array (a merge patch replaces arrays) or `render` (scene-commands.js).
// The object chosen here (state.selected) is the one the editor and the Parameters panel edit.
import * as api from '../api.js';
import { state, set, on } from '../state.js';
import { editScene } from '../scene-commands.js';
import { refreshAssets, isScratch } from '../library.js';
import { backOff, backOffToFit, centreOn } from '../camera-math.js';
import { boundingSphere } from '../mesh-bounds.js';

const MAX_TEXTURES = 4;
const texName = (t) => (typeof t === 'string' ? t : t?.name);

const option = (value, text) => { const o = document.createElement('option'); o.value = value; o.textContent = text; return o; };
/** Fills a <select> with [value, text] entries and chooses `value` (added when not listed). */
const fillSelect = (select, entries, value) => {
  const have = entries.some(([v]) => v === value);
  select.replaceChildren(...entries.map(([v, t]) => option(v, t)), ...(have || value == null ? [] : [option(value, value)]));
  select.value = value ?? '';
};
const focused = (input) => document.activeElement === input;
const objects = () => state.scene.objects;   // read only: edits go through editScene()

/** Shows the scene's objects and render settings, leaving alone the control being used. */
function show(ctx) {
  const { $, $$, list } = ctx;
  const scene = state.scene;
  if (!scene) return;
  const objs = scene.objects || [];
  if (ctx.sel >= objs.length) ctx.select(Math.max(0, objs.length - 1));
  list.replaceChildren(...objs.map((o, i) => option(String(i), `${i + 1}: ${o.mesh} · ${isScratch(o.brdf) ? 'editor' : o.brdf}`)));
  list.value = String(ctx.sel);
  $('.obj-remove').disabled = objs.length <= 1;
  const o = objs[ctx.sel];
  const assets = state.assets || [];
  const label = (a) => (a.builtin ? a.id : `${a.name} (${a.id})`);
  if (o) {
    if (!focused($('.obj-mesh'))) fillSelect($('.obj-mesh'), assets.filter((a) => a.kind === 'mesh').map((a) => [a.id, label(a)]), o.mesh);
    const textures = assets.filter((a) => a.kind === 'texture').map((a) => [a.id, label(a)]);
    for (const s of $$('.obj-tex')) if (!focused(s)) fillSelect(s, [['', '(none)'], ...textures], texName(o.textures?.[Number(s.dataset.i)]) ?? '');
    const brdfs = (state.library || []).filter((b) => !b.broken).map((b) => [b.name, b.name]);
    if (isScratch(o.brdf)) brdfs.unshift([o.brdf, '(the editor\'s text)']);
    if (!focused($('.obj-brdf'))) fillSelect($('.obj-brdf'), brdfs, o.brdf);
    for (const input of $$('.xyz input')) if (!focused(input)) input.value = Number(o[input.dataset.k][Number(input.dataset.i)].toFixed(4));
  }
  if (!focused($('.r-spf'))) $('.r-spf').value = scene.render.samples_per_frame;
  if (!focused($('.r-max'))) $('.r-max').value = scene.render.max_samples;
  if (!focused($('.r-sampling'))) $('.r-sampling').value = scene.render.sampling;
  // Shown in percent; the scene holds a fraction (null: none).
  const t = scene.render.target_error;
  if (!focused($('.r-target'))) $('.r-target').value = t == null ? '' : Number((t * 100).toPrecision(6));
}

/** The list of objects: choose one, add one beside it, remove it. */
function mountList(ctx) {
  const { $, list, send } = ctx;
  list.addEventListener('change', () => { ctx.select(Number(list.value)); show(ctx); });
  $('.obj-add').addEventListener('click', () => {
    send((scene) => {
      const all = scene.objects;
      const base = all[ctx.sel] || { translate: [0, 0, 0] };
      all.push({ mesh: 'sphere', brdf: base.brdf || 'lambert', translate: [base.translate[0] + 2.2, base.translate[1], base.translate[2]] });
      // Beside the selected object, which may put it outside the view: if so, the camera (same
      // direction) centres the objects and backs off until every one is in the frame.
      const cam = scene.camera;
      const spheres = all.map(boundingSphere);
      const aspect = scene.render.width / scene.render.height;
      const patch = { objects: all };
      if (backOffToFit(cam, spheres, aspect) > 0) {
        const centred = { ...cam, position: centreOn(cam, spheres.map((b) => b.center)) };
        patch.camera = { position: backOff(centred.position, cam.yaw, cam.pitch, backOffToFit(centred, spheres, aspect)) };
      }
      return patch;
    });
    ctx.select(objects().length - 1);
  });
  $('.obj-remove').addEventListener('click', () => {
    if (objects().length <= 1) return;   // at least one object stays
    send((scene) => { scene.objects.splice(ctx.sel, 1); return { objects: scene.objects }; });
    ctx.select(Math.min(ctx.sel, objects().length - 1));
    show(ctx);
  });
}

/** The selected object's mesh, BRDF, textures and transform. */
function mountObjectFields(ctx) {
  const { $, $$, patchObject } = ctx;
  $('.obj-mesh').addEventListener('change', (ev) => patchObject({ mesh: ev.target.value }));
  $('.obj-brdf').addEventListener('change', (ev) => {
    const name = ev.target.value;
    patchObject({ brdf: name, params: {} });   // the server fills in the new BRDF's defaults
    const b = state.library.find((x) => x.name === name);
    if (b) set({ brdf: { name, params: b.params } });   // the Parameters panel and the editor follow
  });
  for (const s of $$('.obj-tex')) {
    s.addEventListener('change', () => {
      const old = objects()[ctx.sel].textures || [];
      const slots = $$('.obj-tex').map((x, i) => {
        if (!x.value) return null;
        return texName(old[i]) === x.value ? old[i] : x.value;   // keep an srgb flag set over the API
      });
      while (slots.length && slots.at(-1) === null) slots.pop();
      // Textures bind to iTexture0..3 in order: an empty slot before a used one is `white`.
      patchObject({ textures: slots.map((t) => t ?? 'white').slice(0, MAX_TEXTURES) });
    });
  }
  for (const input of $$('.xyz input')) {
    input.addEventListener('change', () => {
      const v = Number(input.value);
      if (input.value === '' || !Number.isFinite(v)) return;
      const vec = objects()[ctx.sel][input.dataset.k].slice();
      vec[Number(input.dataset.i)] = v;
      patchObject({ [input.dataset.k]: vec });
    });
  }
}

/** The scene-wide render settings: samples per frame, maximum samples, sampling, target error. */
function mountRenderFields({ $, send }) {
  const renderField = (cls, key) => $(cls).addEventListener('change', (ev) => {
    const v = Number(ev.target.value);
    if (Number.isInteger(v) && v > 0) send({ render: { [key]: v } });
  });
  renderField('.r-spf', 'samples_per_frame');
  renderField('.r-max', 'max_samples');
  $('.r-sampling').addEventListener('change', (ev) => send({ render: { sampling: ev.target.value } }));
  $('.r-target').addEventListener('change', (ev) => {
    const text = ev.target.value.trim();
    const v = Number(text);
    if (text === '' || v === 0) send({ render: { target_error: null } });
    else if (Number.isFinite(v) && v > 0 && v < 100) send({ render: { target_error: v / 100 } });
  });
}

/** Uploads of a mesh or a texture, which the selected object then uses. */
function mountUploads(ctx) {
  const { $, status, patchObject } = ctx;
  async function upload(input, kind, apply) {
    const file = input.files?.[0];
    if (!file) return;
    status.textContent = `uploading ${file.name}…`;
    try {
      const asset = await api.uploadAsset(file, kind);
      await refreshAssets();
      apply(asset.id);
      status.textContent = `uploaded ${asset.name} as ${asset.id}`;
    } catch (e) {
      status.textContent = `upload: ${e.message}`;
    } finally {
      input.value = '';
    }
  }
  $('.obj-mesh-upload').addEventListener('change', (ev) => upload(ev.target, 'mesh', (id) => patchObject({ mesh: id })));
  $('.obj-tex-upload').addEventListener('change', (ev) => upload(ev.target, 'texture', (id) => {
    const t = (objects()[ctx.sel].textures || []).slice();
    if (t.length >= MAX_TEXTURES) { status.textContent = `uploaded ${id}; all four texture slots are in use: choose it in one`; return; }
    t.push(id);
    patchObject({ textures: t });
  }));
}

export function mountObjects(el) {
  const status = el.querySelector('.obj-status');
  const ok = () => { if (status.classList.contains('error')) { status.textContent = ''; status.classList.remove('error'); } };
  const failed = (e) => {
    status.textContent = e.message;
    status.classList.add('error');
    set({ status: `objects: ${e.message}` });
  };
  // What the sub-views share: the selected object's index (sel) and how to edit the scene.
  const ctx = {
    $: (c) => el.querySelector(c),
    $$: (c) => [...el.querySelectorAll(c)],
    list: el.querySelector('.obj-list'),
    status,
    sel: state.selected,
    /** Edits the scene (a merge patch, or a function of a copy of the scene returning one). */
    send: (change) => editScene(change).then(ok, failed),
    /** Chooses object i: the Parameters panel and the editor follow its BRDF. */
    async select(i) {
      ctx.sel = i;
      if (state.selected !== i) set({ selected: i });
      const name = state.scene.objects[i]?.brdf;
      if (!name || name === state.brdf?.name) { set({ brdf: state.brdf }); return; }   // rebuild for the new object's values
      const listed = state.library.find((b) => b.name === name);
      try {
        set({ brdf: { name, params: listed ? listed.params : (await api.getBrdf(name)).params } });
      } catch (e) {
        set({ status: `object ${i + 1}: ${e.message}` });
      }
    },
  };
  ctx.patchObject = (changes) => ctx.send((scene) => {
    Object.assign(scene.objects[ctx.sel], changes);
    return { objects: scene.objects };
  });

  // Rebuilt only while its tab is shown: a camera drag answers a scene many times a second.
  const shown = () => !el.closest('.tab-page')?.hidden;
  for (const key of ['scene', 'assets', 'tab', 'library']) on(key, () => shown() && show(ctx));
  mountList(ctx);
  mountObjectFields(ctx);
  mountRenderFields(ctx);
  mountUploads(ctx);
}
