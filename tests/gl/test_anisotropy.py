"""Anisotropic filtering only where it is cheap: none on a
software rasteriser, the driver's 8x on a GPU, an override for both."""

from __future__ import annotations

from axialdeform.gl.context import is_software, texture_anisotropy


class _FakeGPU:
    info = {"GL_RENDERER": "NVIDIA H100 PCIe/PCIe/SSE2"}
    max_anisotropy = 16.0


def test_software_gets_none_a_gpu_gets_8x(ctx, monkeypatch):
    monkeypatch.delenv("AXIALDEFORM_ANISOTROPY", raising=False)
    if is_software(ctx):  # this machine and CI: llvmpipe
        assert texture_anisotropy(ctx) == 1.0
    assert not is_software(_FakeGPU()) and texture_anisotropy(_FakeGPU()) == 8.0
    monkeypatch.setenv("AXIALDEFORM_ANISOTROPY", "4")
    assert texture_anisotropy(_FakeGPU()) == 4.0
    assert texture_anisotropy(ctx) == min(4.0, float(getattr(ctx, "max_anisotropy", 1.0) or 1.0))
    monkeypatch.setenv("AXIALDEFORM_ANISOTROPY", "64")
    assert texture_anisotropy(_FakeGPU()) == 16.0  # never beyond the driver's most
