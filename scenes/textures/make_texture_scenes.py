"""Writes the textures of the texture reference scenes (scenes/texture-*.xml):

- tiles.png (32x24, 8-bit sRGB): a 4 x 3 grid of coloured tiles with a white bar along the top
  row and a black square in the top-left tile, so that orientation (row 0 = top = v 0), a u/v
  swap and sRGB decoding show. Used by texture-bitmap.xml (diffuse reflectance of the OBJ wave
  and, shared by id, the specular_reflectance of the mirror card) and texture-spectral.xml.
- marble.exr (64x32, float32 linear RGB): smooth diagonal veins, values 0.08-0.85, for the
  roughplastic sphere's diffuse_reflectance in texture-bitmap.xml (an EXR: no sRGB decoding).
- texels-4x3.png (4x3, 8-bit sRGB): twelve distinct colours, magnified in texture-filtering.xml
  (nearest vs bilinear, repeat / mirror / clamp); non-square, so a transposed lookup shows.
- roughness.png (32x32, 8-bit grey, one channel): horizontal bands 0.02 ... 0.5 (stored linearly,
  read with raw=true) for the roughdielectric alpha and the blendbsdf weight of
  texture-roughness.xml.
- holes.png (32x32, 8-bit grey): opacity 1 with a 2 x 2 grid of round holes (0) and a
  half-opaque (128) band, for the mask of texture-roughness.xml (read sRGB-decoded, as Mitsuba
  does without raw: 128 -> 0.216).
- glow.png (16x8, 8-bit sRGB): a warm-to-cool horizontal ramp with a bright cell row, all
  values <= 1 (Mitsuba's spectral upsampling clamps to [0, 1]), the area-emitter radiance of
  texture-spectral.xml inside <texture type="d65">.

Run with the references venv: .venv/bin/python scenes/textures/make_texture_scenes.py
"""
import os
import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
HERE = os.path.dirname(os.path.abspath(__file__))


def write_png(name, img, srgb=True):
    fmt = mi.Bitmap.PixelFormat.Y if img.ndim == 2 else mi.Bitmap.PixelFormat.RGB
    b = mi.Bitmap(np.ascontiguousarray(img), pixel_format=fmt)
    b.set_srgb_gamma(srgb)
    b.write(os.path.join(HERE, name))
    print("wrote", name)


# tiles.png
palette = np.array([
    [200, 40, 40], [230, 160, 30], [240, 230, 60], [60, 170, 60],
    [40, 160, 200], [50, 70, 200], [150, 60, 190], [220, 100, 160],
    [120, 80, 40], [160, 160, 160], [90, 200, 150], [250, 200, 170]], np.uint8)
w, h = 32, 24
tiles = np.zeros((h, w, 3), np.uint8)
for j in range(3):
    for i in range(4):
        tiles[j * 8:(j + 1) * 8, i * 8:(i + 1) * 8] = palette[j * 4 + i]
tiles[0:2, :] = 255
tiles[2:6, 1:5] = 0
write_png("tiles.png", tiles)

# marble.exr
w, h = 64, 32
u = (np.arange(w) + 0.5) / w
v = (np.arange(h) + 0.5) / h
U, V = np.meshgrid(u, v)
t = 0.5 + 0.5 * np.sin(2 * np.pi * (2 * U + V) + 1.5 * np.sin(2 * np.pi * 3 * V))
base = np.stack([0.85 - 0.6 * t, 0.75 - 0.55 * t, 0.55 - 0.45 * t], -1)
base[..., 2] += 0.3 * np.exp(-((U - 0.7) ** 2 + (V - 0.3) ** 2) / 0.01)
base = np.clip(base, 0.08, 0.85).astype(np.float32)
mi.Bitmap(base, pixel_format=mi.Bitmap.PixelFormat.RGB).write(os.path.join(HERE, "marble.exr"))
print("wrote marble.exr")

# texels-4x3.png
texels = np.array([
    [[255, 255, 255], [230, 30, 30], [30, 200, 40], [30, 60, 230]],
    [[250, 220, 20], [20, 20, 20], [200, 40, 200], [20, 210, 210]],
    [[120, 120, 120], [255, 140, 0], [140, 80, 30], [180, 220, 120]]], np.uint8)
write_png("texels-4x3.png", texels)

# roughness.png (linear grey levels, read raw)
w = h = 32
levels = np.array([0.02, 0.1, 0.25, 0.5])
rough = np.repeat(np.round(levels * 255).astype(np.uint8), 8)[:, None] * np.ones((1, w), np.uint8)
write_png("roughness.png", rough, srgb=False)

# holes.png
holes = np.full((h, w), 255, np.uint8)
yy, xx = np.mgrid[0:h, 0:w] + 0.5
for cy in (8, 20):
    for cx in (9, 23):
        holes[(xx - cx) ** 2 + (yy - cy) ** 2 < 4.5 ** 2] = 0
holes[27:, :] = 128
write_png("holes.png", holes)

# glow.png
w, h = 16, 8
x = (np.arange(w) + 0.5) / w
glow = np.stack([1.0 - 0.6 * x, 0.55 + 0.2 * np.sin(np.pi * x), 0.3 + 0.7 * x], -1)
glow = np.repeat(glow[None], h, 0) * 0.8
glow[3:5, :, :] = np.array([1.0, 0.95, 0.85])
write_png("glow.png", np.round(glow * 255).astype(np.uint8))
