// Reads what the viewer's <img> shows, inside the page: the current frame of the PNG stream is
// drawn into a small canvas (same origin, so the pixels are readable).
const SIZE = 64;

/** Page function: RGB bytes of the frame on screen, downscaled to 64x64, or null before one. */
export function grabInPage(size) {
  const img = document.querySelector('#viewer img');
  if (!img || !img.complete || !img.naturalWidth) return null;
  const c = document.createElement('canvas');
  c.width = c.height = size;
  const g = c.getContext('2d', { willReadFrequently: true });
  g.drawImage(img, 0, 0, size, size);
  const d = g.getImageData(0, 0, size, size).data;
  const rgb = [];
  for (let i = 0; i < d.length; i += 4) rgb.push(d[i], d[i + 1], d[i + 2]);
  return rgb;
}

export const grab = (page) => page.evaluate(grabInPage, SIZE);

export function variance(px) {
  const mean = px.reduce((a, b) => a + b, 0) / px.length;
  return px.reduce((a, b) => a + (b - mean) ** 2, 0) / px.length;
}

/** Mean absolute difference per channel, 0..255. */
export function meanDiff(a, b) {
  let s = 0;
  for (let i = 0; i < a.length; ++i) s += Math.abs(a[i] - b[i]);
  return s / a.length;
}

/**
 * Waits (polling each animation frame, in the page) for a frame on screen that differs from
 * `before` by more than `threshold` (any frame when `before` is null) and whose pixel variance
 * exceeds `minVariance` (not blank); resolves with the page's performance.now() at that moment.
 */
export async function waitForFrame(page, { before = null, threshold = 0.5, minVariance = 0, timeout = 20000 } = {}) {
  const handle = await page.waitForFunction(({ before, threshold, minVariance, size, grabSrc }) => {
    const grabFn = new Function(`return (${grabSrc})`)();
    const now = grabFn(size);
    if (!now) return false;
    if (before) {
      let s = 0;
      for (let i = 0; i < now.length; ++i) s += Math.abs(now[i] - before[i]);
      if (s / now.length <= threshold) return false;
    }
    if (minVariance > 0) {
      const mean = now.reduce((a, b) => a + b, 0) / now.length;
      const v = now.reduce((a, b) => a + (b - mean) ** 2, 0) / now.length;
      if (v <= minVariance) return false;
    }
    return performance.now();
  }, { before, threshold, minVariance, size: SIZE, grabSrc: grabInPage.toString() }, { polling: 'raf', timeout });
  return handle.jsonValue();
}
