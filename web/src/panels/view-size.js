// How big the view is on screen (never the render resolution: the scene's render.width/height
// stay as they are, the image is scaled). By default the view is as large as its column allows
// above the Parameters panel (style.css); "Fill column" makes it as wide as its column (the
// Parameters then scroll below it); "Fullscreen" shows the view and its bar on the whole screen
// (Fullscreen API; Escape or the button leaves).
import { set, on } from '../state.js';

export function mountViewSize(viewEl, column) {
  const grow = viewEl.querySelector('.view-grow');
  const full = viewEl.querySelector('.view-fullscreen');

  // The image keeps the render's aspect and leaves room for the bar (style.css).
  on('scene', ({ scene }) => {
    const r = scene?.render;
    if (r) viewEl.style.setProperty('--aspect', String(r.width / r.height));
  });
  const bar = viewEl.querySelector('.view-bar');
  new ResizeObserver(() => viewEl.style.setProperty('--bar-height', `${bar.offsetHeight}px`)).observe(bar);

  grow.addEventListener('click', () => {
    const on = column.classList.toggle('grown');
    grow.setAttribute('aria-pressed', String(on));
  });

  full.addEventListener('click', () => {
    if (document.fullscreenElement) document.exitFullscreen();
    else viewEl.requestFullscreen().catch((e) => set({ status: `fullscreen: ${e.message}` }));
  });
  // Browsers leave fullscreen on Escape themselves; a kiosk or headless one may not.
  document.addEventListener('keydown', (ev) => {
    if (ev.key === 'Escape' && document.fullscreenElement === viewEl) document.exitFullscreen();
  });
  document.addEventListener('fullscreenchange', () => {
    const on = document.fullscreenElement === viewEl;
    full.setAttribute('aria-pressed', String(on));
    full.textContent = on ? 'Exit fullscreen' : 'Fullscreen';
    viewEl.querySelector('#viewer').focus();   // keys and the wheel keep working
  });
}
