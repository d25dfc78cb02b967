"""The GL layer: moderngl.  The public names below have their home here; each
lives in the module named beside it (imported on first use).

Modules, in the order of the data flow: ``context`` (contexts, offscreen
targets), ``shaders`` (``glsl/`` with ``#include``), ``buffers`` (the base mesh
and the instanced record), ``material``, ``renderer`` (the instanced draw),
``cull`` (GPU culling and LOD), ``ground``, ``shadow``, ``camera``, ``scene``,
``image`` (pictures), ``bake`` (the GPU engine); ``uniforms``.
"""

from ..core.lazy import attach

_NAMES = {
    "create_context": "context", "Offscreen": "context", "read_pixels": "context",
    "assemble": "shaders", "assemble_text": "shaders", "build_program": "shaders", "deformation_glsl": "shaders",
    "MeshBuffers": "buffers", "InstanceBuffer": "buffers",
    "AxialRenderer": "renderer", "MODES": "renderer",
    "GroundPlane": "ground", "ShadowMap": "shadow",
    "SceneRenderer": "scene",
    "render_image": "image",
}

__getattr__, __dir__, __all__ = attach(__name__, _NAMES)
