"""The bench's "field" scene: a million stones on a plane seen
from a walker's eye height -- most of them outside the view or far away.

Five ways to draw the same frame, timed alternately in ONE process (A B C D
E A B ...) so that load from elsewhere on a shared machine hits them alike:

* ``full`` -- every instance through the vertex shader (``culling=False``);
* ``cull`` -- per-instance GPU frustum culling (``culling=True``, the default),
  on the context's default path: compute + indirect draws on GL >= 4.3;
* ``cull (query)`` -- the same on the GL 3.3 path (transform feedback and a
  query whose count the CPU waits for, ``indirect=False``);
* ``cull+lod`` and ``cull+lod (query)`` -- culling and levels of detail
  (``lod=True``) on each path.

On a GL 3.3 context both paths are the query one.  Each picture is compared
with the ``full`` one: the culled ones must be identical; the LOD ones report
the mean absolute pixel error (fraction of 255) and the share of pixels that
differ.  A second scene frames every instance from above (all visible) and
measures what the culling pass itself costs there, on each path: the pass
alone (``CullPass.run`` + ``ctx.finish()``) and the whole culled frame, each
as a fraction of the unculled frame.

Figures only: nothing here asserts a speed (the goals are reported beside
the numbers).  Pure library code; ``tools/field_bench.py`` is the command.
"""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass, replace

import numpy as np

from ..core.camera import Camera, frame_instances
from ..core.io.mesh import load_mesh
from ..core.look import BACKGROUND
from ..core.options import RenderOptions
from ..core.record import POSITION
from ..core.variation import Variation, random_params
from ..gl.context import Offscreen, create_context
from ..gl.cull import CullQuery
from ..gl.renderer import AxialRenderer

__all__ = ["field_params", "walker_camera", "run_field", "FieldSettings", "format_field", "GOALS"]

#: the issue's goals (reported, never asserted)
GOALS = {"cull_speedup": 5.0, "lod_speedup": 20.0, "lod_mean_error": 0.01, "cull_pass_share": 0.05}
METHODS = {"full": {"culling": False}, "cull": {"culling": True}, "cull (query)": {"culling": True, "indirect": False},
           "cull+lod": {"culling": True, "lod": True}, "cull+lod (query)": {"culling": True, "lod": True, "indirect": False}}
#: the all-visible scene's culled draws: (name in the result, method)
_PASS_METHODS = (("", "cull"), ("query_", "cull (query)"))


def field_params(mesh, count: int, seed: int = 14):
    """``count`` stones on a square grid on the ground (y up), 1.1 L apart."""

    return random_params(mesh, count, seed=seed, variation=Variation(bend=0.12, tilt=(-0.15, 0.15)), placement="grid")


#: walker views: (eye x, eye z as fractions of the field's half width, heading in degrees from +x)
VIEWS = {
    "across": (-0.25, -0.25, 40.0),  # a quarter of the way out, looking across the centre
    "out": (-0.5, 0.0, 180.0),       # half way out, looking out of the field towards its near edge
}


def walker_camera(mesh, params, aspect: float, view: str = "across"):
    """An eye 3 L above the ground inside the field, looking 12 degrees down,
    60 degree vertical field of view, from where :data:`VIEWS` says; the far
    plane reaches past the whole field."""

    L = mesh.axis.length
    pos = params[:, POSITION].astype(np.float64)
    half = float(np.abs(pos[:, [0, 2]]).max()) + L
    fx, fz, heading = VIEWS[view]
    eye = np.array([fx * half, 3.0 * L, fz * half])
    h, down = np.radians(heading), np.radians(12.0)
    direction = np.array([np.cos(down) * np.cos(h), -np.sin(down), np.cos(down) * np.sin(h)])
    return Camera(eye, eye + direction * 10 * L, (0, 1, 0), fovy=60.0, near=0.05 * L, far=4.0 * half)


def _frame(ctx, renderer, target, view, proj) -> float:
    target.use(BACKGROUND)
    ctx.finish()
    start = time.perf_counter()
    renderer.render(view, proj)
    ctx.finish()
    return time.perf_counter() - start


@dataclass(frozen=True)
class FieldSettings:
    """The field scene's settings beside its count, size and frames (:func:`run_field`).

    Attributes
    ----------
    seed : int
    lod_error : float
        Pixels (the LOD renderers').
    samples : int
        MSAA samples of the target (0: none).
    mesh : str or BaseMesh
    views : sequence of str
        The walker's views (``"across"``, ``"out"``).
    all_visible : bool
        Also the all-in-view scene; ``all_visible_frames`` its frames (default ``frames``; its
        unculled frame is the slowest of all).
    """

    seed: int = 14
    lod_error: float = 1.0
    samples: int = 0
    mesh: object = "stone"
    views: tuple = ("across", "out")
    all_visible: bool = True
    all_visible_frames: int | None = None


def run_field(count: int = 1_000_000, size=(800, 600), frames: int = 3, *, ctx=None, progress=None,
              settings: FieldSettings | None = None, **fields) -> dict:
    """Run the field scene; returns a dict of figures (see the module docstring).

    ``progress(text)``: optional callable told what is being drawn.  ``settings``
    (:class:`FieldSettings`) or its fields as keywords: the rest.
    """

    settings = replace(settings or FieldSettings(), **fields)
    seed, lod_error, samples, mesh = settings.seed, settings.lod_error, settings.samples, settings.mesh
    views, all_visible, all_visible_frames = settings.views, settings.all_visible, settings.all_visible_frames
    say = progress or (lambda text: None)
    mesh = load_mesh(mesh) if isinstance(mesh, str) else mesh
    own = ctx is None
    ctx = create_context() if own else ctx
    w, h = size
    out = {"count": int(count), "size": f"{w}x{h}", "samples": samples, "frames": frames, "lod_error": lod_error,
           "mesh": str(mesh.name), "renderer": ctx.info.get("GL_RENDERER", "?"), "gl_version": ctx.version_code}
    try:
        params = field_params(mesh, count, seed)
        renderers = {name: AxialRenderer(ctx, mesh, params, RenderOptions(lod_error=lod_error, **kw)) for name, kw in METHODS.items()}
        try:
            with Offscreen(ctx, (w, h), samples=samples) as target:
                out["views"] = {}
                for view_name in views:
                    cam = walker_camera(mesh, params, w / h, view_name)
                    view, proj = cam.view(), cam.projection(w / h)
                    # pictures, then frames alternately
                    pictures, stats, times = {}, {}, {name: [] for name in renderers}
                    for name, r in renderers.items():
                        say(f"{view_name} view, first frame: {name}")
                        _frame(ctx, r, target, view, proj)
                        pictures[name] = target.read()
                        stats[name] = dict(r.stats)
                    for k in range(frames):
                        for name, r in renderers.items():
                            say(f"{view_name} view, frame {k + 1}/{frames}: {name}")
                            times[name].append(_frame(ctx, r, target, view, proj))
                    full = pictures["full"].astype(np.int16)
                    walker = {}
                    for name in renderers:
                        diff = np.abs(pictures[name].astype(np.int16) - full)
                        walker[name] = {"frame_s": statistics.median(times[name]), "frame_s_all": times[name],
                                        "stats": stats[name], "mean_pixel_error": float(diff.mean() / 255.0),
                                        "pixels_differing": float(diff.any(axis=2).mean()),
                                        "identical": bool(not diff.any())}
                    base = walker["full"]["frame_s"]
                    for name in renderers:
                        walker[name]["speedup"] = base / walker[name]["frame_s"]
                    out["views"][view_name] = {"draws": walker, "camera": {"eye": cam.eye.tolist(),
                                                                           "target": cam.target.tolist(), "fovy": cam.fovy}}
                if not all_visible:
                    return out
                # everything in view: what the culling pass costs
                top = frame_instances(mesh, params, w / h)
                tv, tp = top.view(), top.projection(w / h)
                full_r = renderers["full"]
                for name in ("full",) + tuple(m for _, m in _PASS_METHODS):
                    _frame(ctx, renderers[name], target, tv, tp)
                passes = {m: renderers[m]._cull_passes[False] for _, m in _PASS_METHODS}
                t_full, t_cull, t_pass = [], {m: [] for m in passes}, {m: [] for m in passes}
                av_frames = frames if all_visible_frames is None else int(all_visible_frames)
                out["all_visible_frames"] = av_frames
                for k in range(av_frames):
                    say(f"all in view, frame {k + 1}/{av_frames}")
                    t_full.append(_frame(ctx, full_r, target, tv, tp))
                    for m, cull_pass in passes.items():
                        t_cull[m].append(_frame(ctx, renderers[m], target, tv, tp))
                        ctx.finish()
                        start = time.perf_counter()
                        cull_pass.run(count, 1, CullQuery(tv, tp, frustum=True, center=mesh.axis.center,
                                                          radius=renderers[m].bound_radius))
                        ctx.finish()
                        t_pass[m].append(time.perf_counter() - start)
                f_full = statistics.median(t_full)
                av = out["all_visible"] = {"visible": renderers["cull"].stats["visible"], "full_frame_s": f_full,
                                           "full_frame_s_all": t_full}
                for prefix, m in _PASS_METHODS:
                    f_cull, f_pass = statistics.median(t_cull[m]), statistics.median(t_pass[m])
                    av.update({f"{prefix}indirect": bool(passes[m].indirect), f"{prefix}cull_frame_s": f_cull,
                               f"{prefix}pass_s": f_pass, f"{prefix}pass_share": f_pass / f_full,
                               f"{prefix}frame_overhead": f_cull / f_full - 1.0,
                               f"{prefix}cull_frame_s_all": t_cull[m], f"{prefix}pass_s_all": t_pass[m]})
        finally:
            for r in renderers.values():
                r.release()
    finally:
        if own:
            ctx.release()
    out["goals"] = {}
    for view_name, v in out["views"].items():
        d = v["draws"]
        visible = d["cull"]["stats"]["visible"] / max(out["count"], 1)
        out["goals"][f"{view_name}: cull_speedup"] = {
            "goal": f">= {GOALS['cull_speedup']}x, identical ({visible:.1%} of the instances in view: culling alone "
                    f"removes at most {1 / max(visible, 1e-9):.1f}x of the vertex work)", "value": d["cull"]["speedup"],
            "met": d["cull"]["speedup"] >= GOALS["cull_speedup"] and d["cull"]["identical"]}
        out["goals"][f"{view_name}: lod_speedup"] = {
            "goal": f">= {GOALS['lod_speedup']}x, mean error <= {GOALS['lod_mean_error']:.0%}",
            "value": d["cull+lod"]["speedup"],
            "met": d["cull+lod"]["speedup"] >= GOALS["lod_speedup"]
            and d["cull+lod"]["mean_pixel_error"] <= GOALS["lod_mean_error"]}
    for prefix, _method in _PASS_METHODS:
        share = out["all_visible"][f"{prefix}pass_share"]
        path = "indirect draws" if out["all_visible"][f"{prefix}indirect"] else "query wait"
        out["goals"][f"cull_pass_share ({path})"] = {
            "goal": f"<= {GOALS['cull_pass_share']:.0%} of an all-visible frame", "value": share,
            "met": share <= GOALS["cull_pass_share"]}
    return out


def format_field(res: dict) -> str:
    """A short Markdown report of :func:`run_field`'s result."""
    lines = [f"Field scene: {res['count']} x {res['mesh']}, {res['size']}, {res['samples']} MSAA samples, "
             f"median of {res['frames']} alternated frames; {res['renderer']} (GL {res['gl_version']}).", "",
             "| view | draw | frame | speed-up | drawn | per LOD level | vertices | mean pixel error | pixels differing |",
             "|---|---|---|---|---|---|---|---|---|"]
    rows = [(view_name, name, row) for view_name, v in res["views"].items() for name, row in v["draws"].items()]
    for view_name, name, row in rows:
        st = row["stats"]
        lines.append(f"| {view_name} | {name} | {row['frame_s'] * 1000:.1f} ms | {row['speedup']:.1f}x | "
                     f"{st['visible']} ({st['visible'] / max(st['submitted'], 1):.1%}) | "
                     f"{' / '.join(map(str, st['levels'])) if st.get('lod') else '-'} | {st['vertices']} | "
                     f"{row['mean_pixel_error']:.4%} | {row['pixels_differing']:.3%} |")
    if "all_visible" not in res:
        return "\n".join(lines)
    av = res["all_visible"]
    lines += ["", f"All {av['visible']} in view (median of {res.get('all_visible_frames', res['frames'])} alternated "
              f"frames): unculled frame {av['full_frame_s'] * 1000:.1f} ms."]
    for prefix, m in _PASS_METHODS:
        path = "indirect draws" if av[f"{prefix}indirect"] else "query wait"
        lines.append(f"- {m.split(' (')[0]} ({path}): culled frame {av[f'{prefix}cull_frame_s'] * 1000:.1f} ms "
                     f"({av[f'{prefix}frame_overhead']:+.1%}), the culling pass alone "
                     f"{av[f'{prefix}pass_s'] * 1000:.1f} ms ({av[f'{prefix}pass_share']:.1%} of the unculled frame).")
    lines.append("")
    for key, g in res["goals"].items():
        lines.append(f"- {key}: goal {g['goal']}; measured {g['value']:.3g} -> {'met' if g['met'] else 'NOT met'}")
    return "\n".join(lines)
