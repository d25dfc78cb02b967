// The brush of a generated layer (the Python library's core/brush.py, stroke for stroke): a mask over the
// ground the layer's density map covers, white grows and black does not; it multiplies the density map
// (no map: it is one), so painting never adds instances the recipe would not make.  Each stroke gives the
// generator the new density and the tiles are made again on the mesh's next update.  `png()` is the mask
// as the library reads it beside a scene file (SCENE-LAYER-mask.png, 8-bit grey).
import { AxialError, crc32 } from './adp.js';

/** Pixels a side of a new mask (core/brush.py's MASK_SIZE). */
export const MASK_SIZE = 512;

function checkGrid(grid, what) {
  if (!grid || !(grid.data instanceof Float32Array) || !(grid.cols > 0) || !(grid.rows > 0) ||
      grid.data.length !== grid.cols * grid.rows) {
    throw new AxialError(`AxialBrush: ${what}: expected {data: Float32Array of cols x rows, cols, rows}`);
  }
  return grid;
}

export class AxialBrush {
  /**
   * mesh: a generated layer (an AxialInstancedMesh made with {generate: recipe}).  ground: {area: [x0, z0, x1, z1], the ground its density map covers (the
   * height map's, or on flat ground the layer's extent), wrap: whether the map repeats (flat ground),
   * density: the layer's own density map ({data, cols, rows}; null: none), mask: the mask painted so far
   * (null: a new one, where everything grows)}.
   */
  constructor(mesh, ground) {
    if (!mesh || !mesh.recipe) throw new AxialError('AxialBrush: expected a generated layer (an AxialInstancedMesh made with {generate: recipe})');
    const area = ground && ground.area;
    if (!Array.isArray(area) || area.length !== 4 || !area.every(Number.isFinite) || !(area[2] > area[0]) ||
        !(area[3] > area[1])) {
      throw new AxialError('AxialBrush: ground.area: expected [x0, z0, x1, z1] with x1 > x0 and z1 > z0');
    }
    this.mesh = mesh;
    this.area = area;
    this.wrap = !!ground.wrap;
    this.density = ground.density ? checkGrid(ground.density, 'ground.density') : null;
    const d = this.density;
    const rows = Math.max(MASK_SIZE, d ? d.rows : 0), cols = Math.max(MASK_SIZE, d ? d.cols : 0);
    this.mask = ground.mask ? checkGrid(ground.mask, 'ground.mask') : { data: new Float32Array(rows * cols).fill(1), cols, rows };
  }

  /** Paint (or erase) a round dab at (x, z) on the ground: every mask pixel whose centre lies within
   * `radius`.  Whether any pixel changed; if so the mesh's tiles are made again with the new density. */
  stroke(x, z, radius, erase = false) {
    if (![x, z, radius].every(Number.isFinite) || !(radius > 0)) {
      throw new AxialError(`brush: expected a finite x, z and a radius > 0, found ${x}, ${z}, ${radius}`);
    }
    const { cols, rows, data } = this.mask, [x0, z0, x1, z1] = this.area;
    const px = (x1 - x0) / cols, pz = (z1 - z0) / rows, value = erase ? 0 : 1;
    const c0 = Math.max(Math.floor((x - radius - x0) / px), 0), c1 = Math.min(Math.ceil((x + radius - x0) / px), cols);
    const r0 = Math.max(Math.floor((z - radius - z0) / pz), 0), r1 = Math.min(Math.ceil((z + radius - z0) / pz), rows);
    let changed = false;
    for (let r = r0; r < r1; r++) {
      const dz = z0 + (r + 0.5) * pz - z;
      for (let c = c0; c < c1; c++) {
        const dx = x0 + (c + 0.5) * px - x;
        if (dx * dx + dz * dz <= radius * radius && data[r * cols + c] !== value) {
          data[r * cols + c] = value;
          changed = true;
        }
      }
    }
    if (changed) this.apply();
    return changed;
  }

  /** The density the generator reads: the density map (its nearest pixel under each mask pixel) times the
   * mask, on the mask's grid (core/brush.py's fold). */
  fold() {
    const { cols, rows, data } = this.mask, d = this.density;
    if (!d) return Float32Array.from(data);
    const out = new Float32Array(rows * cols);
    for (let r = 0; r < rows; r++) {
      const dr = Math.min(Math.floor(((r + 0.5) * d.rows) / rows), d.rows - 1);
      for (let c = 0; c < cols; c++) {
        const dc = Math.min(Math.floor(((c + 0.5) * d.cols) / cols), d.cols - 1);
        out[r * cols + c] = d.data[dr * d.cols + dc] * data[r * cols + c];
      }
    }
    return out;
  }

  /** Give the mesh the folded density, placed over the area as the library places it (GroundMaps.of). */
  apply() {
    const { cols, rows } = this.mask, [x0, z0, x1, z1] = this.area, f = Math.fround;
    this.mesh.setDensity({ data: this.fold(), cols, rows },
      { d_lo: [f(x0), f(z0)], d_inv: [f(cols / (x1 - x0)), f(rows / (z1 - z0))], d_wrap: this.wrap });
  }

  /** The mask as an 8-bit grey PNG (Uint8Array), first row at z0: what the library reads as the layer's mask. */
  async png() {
    const { cols, rows, data } = this.mask;
    const raw = new Uint8Array(rows * (cols + 1)); // each row: filter 0, then its pixels
    for (let r = 0; r < rows; r++) {
      for (let c = 0; c < cols; c++) raw[r * (cols + 1) + 1 + c] = Math.round(Math.min(Math.max(data[r * cols + c], 0), 1) * 255);
    }
    const zlib = new Uint8Array(await new Response(new Blob([raw]).stream().pipeThrough(new CompressionStream('deflate'))).arrayBuffer());
    const chunk = (type, body) => {
      const out = new Uint8Array(12 + body.length), view = new DataView(out.buffer);
      view.setUint32(0, body.length);
      out.set(new TextEncoder().encode(type), 4);
      out.set(body, 8);
      view.setUint32(8 + body.length, crc32(out.subarray(4, 8 + body.length)));
      return out;
    };
    const head = new Uint8Array(13), hv = new DataView(head.buffer);
    hv.setUint32(0, cols);
    hv.setUint32(4, rows);
    head.set([8, 0, 0, 0, 0], 8); // 8 bits, grey, deflate, no filter, no interlace
    const parts = [new Uint8Array([137, 80, 78, 71, 13, 10, 26, 10]), chunk('IHDR', head), chunk('IDAT', zlib),
      chunk('IEND', new Uint8Array(0))];
    const out = new Uint8Array(parts.reduce((n, p) => n + p.length, 0));
    let at = 0;
    for (const p of parts) { out.set(p, at); at += p.length; }
    return out;
  }
}
