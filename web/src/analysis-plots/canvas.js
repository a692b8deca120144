// A 2D canvas sized in CSS pixels and drawn at the screen's pixel density.
export function prepare(canvas, width, height) {
  const dpr = window.devicePixelRatio || 1;
  canvas.width = Math.round(width * dpr);
  canvas.height = Math.round(height * dpr);
  canvas.style.width = `${width}px`;
  canvas.style.height = `${height}px`;
  const g = canvas.getContext('2d');
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  g.clearRect(0, 0, width, height);
  g.font = '11px system-ui, sans-serif';
  return g;
}

/** The width a plot may take: its container's, at least `min`. */
export const widthOf = (el, min = 200) => Math.max(min, Math.floor(el.parentElement?.clientWidth || min));
