// Browser checks of the layout and the camera, run by run.mjs after checks.mjs:
// at 1024x700 and 1400x900, with ggx and with disney (the BRDF with the most parameters), no
// two labels, readouts, controls or buttons of the Parameters panel overlap, and each is shown
// whole inside the panel; orbit (the default camera) turns about the selected object and keeps
// its distance; "Frame object" brings a far camera back to the distance that fits the object;
// "Reset view", "Fill column" and fullscreen do what they say. Each viewport gets a browser
// context and a session of its own.
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { http, until, sleep, capSamples, settle, project } from './checks.mjs';

const SIZES = [[1024, 700], [1400, 900]];
const LOOK = 0.25;     // degrees per pixel dragged: the UI's default (state.speeds.look)
const MARGIN = 1.15;   // the framed bounding sphere spans 1 / MARGIN of the tightest half-angle

/**
 * Page function: the boxes of everything one reads or clicks in `root` (labels and names,
 * readouts, sliders and other inputs, selects, buttons), with whether each is rendered and
 * whether its text is cut (scrollWidth over clientWidth), and the root's own box.
 */
function boxesIn(root) {
  const el = document.querySelector(root);
  const box = (e) => { const r = e.getBoundingClientRect(); return { x: r.left, y: r.top, w: r.width, h: r.height }; };
  // A colour or check box row has no number to read: its readout is empty and takes no room.
  const items = [...el.querySelectorAll('strong, .param-name, output, input, select, button')]
    .filter((e) => e.tagName !== 'OUTPUT' || e.textContent !== '').map((e) => ({
    what: `${e.tagName.toLowerCase()}${e.className ? `.${e.className}` : ''}` +
      `${e.closest('.param') ? `[${e.closest('.param').querySelector('.param-name').textContent}]` : ''}` +
      `${e.tagName === 'BUTTON' ? ` "${e.textContent}"` : ''}`,
    ...box(e),
    shown: e.checkVisibility({ visibilityProperty: true, opacityProperty: true }),
    cut: e.matches('.param-name, output') && e.scrollWidth > e.clientWidth,
    text: e.textContent,
    title: e.title,
  }));
  return { root: box(el), viewport: { w: innerWidth, h: innerHeight }, items };
}

/** The pairs of boxes that overlap by more than half a pixel both ways (touching is fine). */
function overlaps(items) {
  const found = [];
  for (let i = 0; i < items.length; ++i) {
    for (let j = i + 1; j < items.length; ++j) {
      const a = items[i], b = items[j];
      const ox = Math.min(a.x + a.w, b.x + b.w) - Math.max(a.x, b.x);
      const oy = Math.min(a.y + a.h, b.y + b.h) - Math.max(a.y, b.y);
      if (ox > 0.5 && oy > 0.5) found.push(`${a.what} x ${b.what} (${ox.toFixed(1)} x ${oy.toFixed(1)} px)`);
    }
  }
  return found;
}

/** Every item shown, of non-zero size, inside `outer` (and `outer` inside the viewport). */
function assertShownInside({ root: outer, viewport, items }, where) {
  assert.ok(outer.x >= -0.5 && outer.y >= -0.5 && outer.x + outer.w <= viewport.w + 0.5 && outer.y + outer.h <= viewport.h + 0.5,
    `${where} lies inside the window (${JSON.stringify(outer)} in ${viewport.w}x${viewport.h})`);
  for (const b of items) {
    assert.ok(b.shown && b.w > 0 && b.h > 0, `${where}: ${b.what} is shown (${b.w.toFixed(1)} x ${b.h.toFixed(1)})`);
    assert.ok(b.x >= outer.x - 0.5 && b.y >= outer.y - 0.5 && b.x + b.w <= outer.x + outer.w + 0.5 && b.y + b.h <= outer.y + outer.h + 0.5,
      `${where}: ${b.what} lies inside (${JSON.stringify(b)} in ${JSON.stringify(outer)})`);
  }
}

const shot = (env, page, name) => page.screenshot({ path: join(env.artifacts, `${name}.png`) });
const scene = (env, sid) => http(env, 'GET', `/api/sessions/${sid}/scene`);
const dist = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
const tightHalfAngle = (fov, aspect) => Math.min(fov * Math.PI / 360, Math.atan(Math.tan(fov * Math.PI / 360) * aspect));

/** Opens the UI in a window of w x h in a context of its own; waits for a frame. */
async function openSized(env, w, h) {
  const context = await env.context.browser().newContext({ viewport: { width: w, height: h } });
  const page = await context.newPage();
  page.errors = [];
  page.on('console', (m) => { if (m.type() === 'error') page.errors.push(`${w}x${h} console: ${m.text()}`); });
  page.on('pageerror', (e) => page.errors.push(`${w}x${h} page error: ${e.message}`));
  await page.goto(env.server.url + '/');
  await env.waitForFrame(page, { minVariance: 20, timeout: 60000 });   // a loaded machine is slow to the first
  const sid = new URL(page.url()).searchParams.get('session');
  await capSamples(env, sid);   // frames that stop changing, so a new one can be told apart
  return { context, page, sid };
}

/** The session's camera once it has stopped changing (the last PATCH of a drag may be in flight). */
async function stillCamera(env, sid) {
  let last = null;
  return until('the camera to stop', async () => {
    const c = (await scene(env, sid)).camera;
    const same = last && JSON.stringify(c) === JSON.stringify(last);
    last = c;
    if (!same) await sleep(150);
    return same && c;
  });
}

/** Drags the mouse across the view by (dx, dy) pixels from its centre. */
async function drag(page, dx, dy) {
  const r = await page.locator('#viewer').boundingBox();
  const x = r.x + r.width / 2, y = r.y + r.height / 2;
  await page.mouse.move(x, y);
  await page.mouse.down();
  await page.mouse.move(x + dx, y + dy, { steps: 12 });
  await page.mouse.up();
}

/** Opens BRDF `name` from the library; resolves with its parameter declarations once shown. */
async function useBrdf(env, page, sid, name) {
  const declared = (await http(env, 'GET', `/api/brdfs/${name}`)).params;
  if ((await scene(env, sid)).objects[0].brdf !== name) await page.selectOption('#library .library-list', name);
  await until(`the Parameters panel to show ${name}'s parameters`, async () =>
    JSON.stringify(await page.locator('#params .param-name').allTextContents()) === JSON.stringify(declared.map((p) => p.name)));
  return declared;
}

/** Sets translate/scale of the selected object through the Objects tab, as a user does. */
async function placeObject(page, changes) {
  await page.click('.tabs [data-tab="tab-objects"]');
  for (const [k, v] of Object.entries(changes)) {
    for (let i = 0; i < 3; ++i) {
      const input = `#objects .xyz input[data-k="${k}"][data-i="${i}"]`;
      await page.fill(input, String(v[i]));
      await page.press(input, 'Enter');
    }
  }
  await page.click('.tabs [data-tab="tab-editor"]');
}

export const layoutChecks = [
  ['Parameters: no two labels, readouts, controls or buttons overlap at 1024x700 and 1400x900 (ggx, disney)', async (env) => {
    env.sized = {};
    for (const [w, h] of SIZES) {
      const tab = await openSized(env, w, h);
      env.sized[`${w}x${h}`] = tab;
      await tab.page.waitForSelector('#library .library-list option[value="disney"]', { state: 'attached' });
      for (const brdf of ['ggx', 'disney']) {
        const declared = await useBrdf(env, tab.page, tab.sid, brdf);
        await sleep(300);   // the preset list arrives after the rows
        const m = await tab.page.evaluate(boxesIn, '#params');
        const where = `${w}x${h} ${brdf}`;
        const found = overlaps(m.items);
        const view = await tab.page.locator('#viewer').boundingBox();
        console.log(`LAYOUT ${where}: Parameters ${m.root.w.toFixed(0)}x${m.root.h.toFixed(0)} px, ${m.items.length} boxes, ` +
          `${found.length} overlapping pairs; view ${view.width.toFixed(0)} px`);
        await shot(env, tab.page, `layout-${w}x${h}-${brdf}`);
        assert.deepEqual(found, [], `${where}: overlapping boxes`);
        assertShownInside(m, `${where} Parameters panel`);
        // Every declared parameter has its name, control and reset button, and a float its readout.
        for (const { name, type } of declared) {
          assert.equal(m.items.filter((b) => b.what.endsWith(`[${name}]`) || b.what.includes(`[${name}] `)).length,
            type === 'float' ? 4 : 3, `${where}: the boxes of ${name}`);
        }
        // Names and readouts are shown whole at these sizes; a name always carries its title.
        for (const b of m.items.filter((i) => i.what.startsWith('span.param-name'))) assert.equal(b.title, b.text, `${where}: title of ${b.text}`);
        assert.deepEqual(m.items.filter((b) => b.cut).map((b) => `${b.what} "${b.text}"`), [], `${where}: cut names or readouts`);
        // The view is not squeezed by the panel below it.
        assert.ok(view.width >= 300, `${where}: the view is ${view.width} px wide`);
        // The bar under the view: its buttons do not overlap either.
        const bar = await tab.page.evaluate(boxesIn, '#view .view-bar');
        assert.deepEqual(overlaps(bar.items), [], `${where}: overlapping buttons in the view's bar`);
        assertShownInside(bar, `${where} view bar`);
      }
    }
  }],

  ['orbit, the default: a drag turns the camera about the selected object at a constant distance; first person turns in place', async (env) => {
    const { page, sid } = env.sized['1400x900'];
    await page.bringToFront();   // a background page's animation frames are throttled
    assert.equal(await page.getAttribute('#view [data-mode="orbit"]', 'aria-pressed'), 'true', 'orbit is the default mode');
    const before = await settle(env, page, sid);
    const s0 = await scene(env, sid);
    const c0 = s0.camera, target = s0.objects[0].translate, aspect = s0.render.width / s0.render.height;
    const d0 = dist(c0.position, target);

    await drag(page, 120, -60);   // right and up: yaw -30, pitch +15 at the default speed
    const c1 = await until('the camera to orbit', async () => {
      const c = await stillCamera(env, sid);
      return Math.abs(c.yaw - (c0.yaw - 120 * LOOK)) < 2 && Math.abs(c.pitch - (c0.pitch + 60 * LOOK)) < 2 && c;
    });
    const ndc = project(c1, target, aspect);
    console.log(`ORBIT camera ${JSON.stringify(c0)} -> ${JSON.stringify(c1)}; distance ${d0.toFixed(4)} -> ` +
      `${dist(c1.position, target).toFixed(4)}; target at (${ndc.x.toFixed(4)}, ${ndc.y.toFixed(4)})`);
    assert.ok(dist(c1.position, c0.position) > 1, 'the camera moved');
    assert.ok(Math.abs(dist(c1.position, target) - d0) < 1e-3 * d0, 'the distance to the object stays the same');
    assert.ok(ndc.z > 0 && Math.abs(ndc.x) < 1e-3 && Math.abs(ndc.y) < 1e-3, 'the object stays in the centre of the view');
    await env.waitForFrame(page, { before, threshold: 0.5 });
    await shot(env, page, 'layout-orbit');

    // First person: the same drag turns the camera where it stands; the object leaves the centre.
    await page.click('#view [data-mode="fly"]');
    assert.equal(await page.getAttribute('#view [data-mode="fly"]', 'aria-pressed'), 'true');
    await drag(page, 120, 0);
    const c2 = await until('the camera to turn', async () => {
      const c = await stillCamera(env, sid);
      return Math.abs(c.yaw - (c1.yaw - 120 * LOOK)) < 2 && c;
    });
    assert.ok(dist(c2.position, c1.position) < 1e-4, `first person keeps the position (${c1.position} -> ${c2.position})`);
    assert.ok(Math.abs(project(c2, target, aspect).x) > 0.3, 'the object is no longer in the centre');
    await page.click('#view [data-mode="orbit"]');
  }],

  ['the wheel changes the orbit distance within limits; Frame object brings a far camera back to the fitting distance; Reset view', async (env) => {
    const { page, sid } = env.sized['1400x900'];
    await page.bringToFront();
    // An object off the origin and twice as large: a sphere of radius 2 at (1, 0.5, -2).
    const center = [1, 0.5, -2], radius = 2;
    await placeObject(page, { translate: center, scale: [radius, radius, radius] });
    await until('the object placed', async () => {
      const o = (await scene(env, sid)).objects[0];
      return JSON.stringify([o.translate, o.scale]) === JSON.stringify([center, [radius, radius, radius]]);
    }).catch(async (e) => { throw new Error(`${e.message}: ${JSON.stringify((await scene(env, sid)).objects)}`); });
    const s0 = await scene(env, sid);
    const aspect = s0.render.width / s0.render.height;
    const fit = (MARGIN * radius) / Math.sin(tightHalfAngle(s0.camera.fov, aspect));

    // Wheel out: farther along the line to the object's centre, which stays where it appears,
    // up to 20 fitting distances.
    const c0 = await stillCamera(env, sid);
    const ndc0 = project(c0, center, aspect);
    const r = await page.locator('#viewer').boundingBox();
    await page.mouse.move(r.x + r.width / 2, r.y + r.height / 2);
    for (let i = 0; i < 40; ++i) await page.mouse.wheel(0, 400);
    const far = await until('the camera to back off', async () => {
      const c = await stillCamera(env, sid);
      return dist(c.position, center) > 10 * fit && c;
    });
    const ndc1 = project(far, center, aspect);
    console.log(`ZOOM distance ${dist(c0.position, center).toFixed(3)} -> ${dist(far.position, center).toFixed(3)} ` +
      `(limit ${(20 * fit).toFixed(3)}); centre at (${ndc0.x.toFixed(4)}, ${ndc0.y.toFixed(4)}) -> (${ndc1.x.toFixed(4)}, ${ndc1.y.toFixed(4)})`);
    assert.ok(dist(far.position, center) <= 20 * fit * (1 + 1e-4), 'the wheel stops at 20 fitting distances');
    assert.ok(Math.abs(ndc1.x - ndc0.x) < 1e-3 && Math.abs(ndc1.y - ndc0.y) < 1e-3, 'the object stays where it appears');

    // Farther still and looking away, through the camera form in first person.
    await page.click('#view [data-mode="fly"]');
    for (const [name, v] of [['px', 60], ['py', 20], ['pz', 90], ['yaw', 70], ['pitch', -10]]) {
      await page.fill(`#camera input[name="${name}"]`, String(v));
      await page.press(`#camera input[name="${name}"]`, 'Enter');
    }
    await until('the camera far away', async () => (await stillCamera(env, sid)).position[2] === 90);
    const before = await settle(env, page, sid);

    await page.click('#view .view-frame');
    const framed = await until('the camera framed', async () => {
      const c = await stillCamera(env, sid);
      return Math.abs(dist(c.position, center) - fit) < 1e-3 * fit && c;
    }, 10000).catch(async (e) => { throw new Error(`${e.message}: ${JSON.stringify(await scene(env, sid))}, fit ${fit}`); });
    const ndc = project(framed, center, aspect);
    const spans = Math.asin(radius / dist(framed.position, center)), half = tightHalfAngle(framed.fov, aspect);
    console.log(`FRAME camera ${JSON.stringify(framed)}: distance ${dist(framed.position, center).toFixed(4)}, ` +
      `formula ${MARGIN} * ${radius} / sin(${(half * 180 / Math.PI).toFixed(2)} deg) = ${fit.toFixed(4)}; ` +
      `the sphere spans ${(spans * 180 / Math.PI).toFixed(2)} of ${(half * 180 / Math.PI).toFixed(2)} deg`);
    assert.ok(Math.abs(framed.yaw - 70) < 1e-3 && Math.abs(framed.pitch + 10) < 1e-3, 'Frame keeps the direction of view');
    assert.ok(ndc.z > 0 && Math.abs(ndc.x) < 1e-3 && Math.abs(ndc.y) < 1e-3, 'the object is in the centre');
    assert.ok(spans < half && spans > 0.8 * half, 'the object fills the view without leaving it');
    await env.waitForFrame(page, { before, threshold: 0.5 });
    await shot(env, page, 'layout-framed');

    await page.click('#view .view-reset');
    await until('the default camera', async () =>
      JSON.stringify(await stillCamera(env, sid)) === JSON.stringify({ fov: 45, pitch: 0, position: [0, 0, 3], yaw: 0 }));
    await until('the form to show it', async () => Number(await page.inputValue('#camera input[name="pz"]')) === 3, 5000);
    await page.click('#view [data-mode="orbit"]');
  }],

  ['Fill column widens the view to its column; Fullscreen shows it on the whole screen, Escape leaves', async (env) => {
    const { page } = env.sized['1024x700'];
    await page.bringToFront();
    const width = async () => (await page.locator('#viewer').boundingBox()).width;
    const column = () => page.evaluate(() => { const l = document.querySelector('main .left'); return l.clientWidth; });
    const w0 = await width();
    assert.ok(w0 < (await column()) - 20, `with disney the view (${w0} px) is narrower than its column (${await column()} px)`);
    await page.click('#view .view-grow');
    await until('the view to fill its column', async () => Math.abs((await width()) - (await column())) < 1, 5000);
    assert.equal(await page.getAttribute('#view .view-grow', 'aria-pressed'), 'true');
    await shot(env, page, 'layout-1024x700-fill-column');
    await page.click('#view .view-grow');
    await until('the view back to its size', async () => Math.abs((await width()) - w0) < 1, 5000);

    await page.click('#view .view-fullscreen');
    await until('fullscreen', () => page.evaluate(() => document.fullscreenElement?.id === 'view'), 5000);
    await until('the view to grow', async () => (await width()) > w0 + 100, 5000);
    await shot(env, page, 'layout-fullscreen');
    await page.keyboard.press('Escape');
    await until('fullscreen left', () => page.evaluate(() => document.fullscreenElement === null), 5000);
    await until('the view back to its size', async () => Math.abs((await width()) - w0) < 1, 5000);

    for (const { page: p } of Object.values(env.sized)) assert.deepEqual(p.errors, [], 'no console errors');
    for (const { context } of Object.values(env.sized)) await context.close();
  }],
];
