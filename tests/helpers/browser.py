"""One page of ``axialdeform web`` (or the widget's front end in a minimal anywidget harness) in
Chromium, its console errors collected, and the silhouette comparisons the page tests make."""

from __future__ import annotations

import base64
import json

import numpy as np

#: the page tests' canvas (width, height)
SIZE = (400, 300)
#: the landscape example's sky (its scene file's background)
SKY = (0.80, 0.87, 0.95)


class Visit:
    """One page in the browser with its console errors collected."""

    def __init__(self, browser, url, size=SIZE):
        self.page = browser.new_page(viewport={"width": size[0], "height": size[1] + 40})
        self.errors = []
        self.page.on("console", lambda m: self.errors.append(m.text) if m.type == "error" else None)
        self.page.on("pageerror", lambda e: self.errors.append(str(e)))
        self.page.goto(url)
        self.page.wait_for_function("window.axialdeform && window.axialdeform.ready !== undefined", timeout=120_000)
        self.state = self.page.evaluate("window.axialdeform")

    def silhouette(self) -> np.ndarray:
        from io import BytesIO

        from PIL import Image

        box = self.page.locator(".axd-stage").bounding_box()
        png = self.page.screenshot(clip=box)  # no "stable element" wait: the status line keeps changing
        return np.asarray(Image.open(BytesIO(png)).convert("RGB"))

    def close(self):
        self.page.close()


def mask(image: np.ndarray, background) -> np.ndarray:
    bg = np.asarray(background) * 255.0
    return np.abs(image.astype(np.float64) - bg).max(axis=2) > 12


def iou(a: np.ndarray, b: np.ndarray, background) -> float:
    ma, mb = mask(a, background), mask(b, background)
    return float((ma & mb).sum() / max((ma | mb).sum(), 1))


def widget_state(w) -> dict:
    """A widget's synced state as ``widget_page`` takes it (bytes as base64)."""
    state = {k: getattr(w, k) for k in ("config", "mesh_glb", "params_adp", "_sources")}
    return {k: ({"b64": base64.b64encode(v).decode()} if isinstance(v, bytes) else v) for k, v in state.items()}


def widget_page(browser, tmp_path, state: dict, esm: str):
    """The widget's ESM run in Chromium against a minimal anywidget model
    (get/set/on/off/save_changes over the synced state; bytes arrive as
    DataView, as ipywidgets delivers them).  ``state``: name -> value, or
    {"b64": ...} for bytes.  Returns (page, console errors)."""
    harness = tmp_path / "widget harness ü.html"
    harness.write_text("""<!doctype html><meta charset="utf-8"><link rel="icon" href="data:,"><body><div id="out"></div>
<script type="module">
const state = JSON.parse(document.getElementById('state').textContent);
const dv = (b64) => { const s = atob(b64); const a = new Uint8Array(s.length);
  for (let i = 0; i < s.length; i++) a[i] = s.charCodeAt(i); return new DataView(a.buffer); };
const data = {}; for (const [k, v] of Object.entries(state)) data[k] = v && v.b64 !== undefined ? dv(v.b64)
  : k === 'files' ? Object.fromEntries(Object.entries(v).map(([n, x]) => [n, dv(x.b64)])) : v;
const listeners = {};
const model = { get: (k) => data[k], set: (k, v) => { data[k] = v; (listeners['change:' + k] || []).forEach((f) => f()); },
  on: (e, f) => { (listeners[e] = listeners[e] || []).push(f); },
  off: (e, f) => { listeners[e] = (listeners[e] || []).filter((g) => g !== f); },
  save_changes: () => { window.widgetStatus = data.status; } };
window.widgetModel = model; window.toDataView = dv;
const esm = await import(URL.createObjectURL(new Blob([document.getElementById('esm').textContent], {type: 'text/javascript'})));
window.cleanup = await esm.default.render({ model, el: document.getElementById('out') });
</script>
<script type="application/json" id="state">""" + json.dumps(state).replace("</", "<\\/") + """</script>
<script type="text/plain" id="esm">""" + esm.replace("</script", "<\\/script") + """</script>""", encoding="utf-8")
    page = browser.new_page(viewport={"width": SIZE[0], "height": SIZE[1] + 40})
    errors = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(harness.as_uri())
    page.wait_for_function("window.widgetStatus !== undefined", timeout=120_000)
    return page, errors
