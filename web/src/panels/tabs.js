// Tabs of the right-hand column (editor, objects, environment, test, help): one page shown at a
// time so everything fits 1280x720. The chosen tab is kept in the URL hash (#tab-test).
import { set } from '../state.js';

export function mountTabs(nav) {
  const buttons = [...nav.querySelectorAll('[data-tab]')];
  const show = (id) => {
    if (!buttons.some((b) => b.dataset.tab === id)) id = buttons[0].dataset.tab;
    for (const b of buttons) {
      const on = b.dataset.tab === id;
      b.setAttribute('aria-selected', String(on));
      document.getElementById(b.dataset.tab).hidden = !on;
    }
    set({ tab: id });
  };
  for (const b of buttons) {
    b.addEventListener('click', () => {
      show(b.dataset.tab);
      history.replaceState(null, '', `${location.pathname}${location.search}#${b.dataset.tab}`);
    });
  }
  show(location.hash.slice(1));
}
