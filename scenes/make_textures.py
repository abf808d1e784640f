"""Draw the arena's wall textures into scenes/textures/*.png.

Run once by hand (`python scenes/make_textures.py`); the PNGs are committed and
nothing is generated at run time. Only numpy and zlib, so the pictures come out
the same on any machine. Each texture is a 256 x 64 RGB image: one wall is
7.5 m long and 1 m high, so a texture repeated twice along a wall keeps
features roughly square.
"""

from __future__ import annotations

import pathlib
import struct
import zlib

import numpy as np

W, H = 256, 64
OUT = pathlib.Path(__file__).resolve().parent / "textures"


def write_png(path: pathlib.Path, rgb: np.ndarray) -> None:
    rgb = np.ascontiguousarray(rgb, dtype=np.uint8)
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(h))

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    path.write_bytes(png)


def value_noise(rng: np.random.Generator, cells_x: int, cells_y: int) -> np.ndarray:
    """Smooth noise in [0, 1], tileable horizontally, bilinear between random lattice values."""
    lattice = rng.random((cells_y + 1, cells_x))
    lattice = np.concatenate([lattice, lattice[:, :1]], axis=1)
    y = np.linspace(0, cells_y, H, endpoint=False)
    x = np.linspace(0, cells_x, W, endpoint=False)
    y0, x0 = np.floor(y).astype(int), np.floor(x).astype(int)
    fy, fx = (y - y0)[:, None], (x - x0)[None, :]
    fy, fx = fy * fy * (3 - 2 * fy), fx * fx * (3 - 2 * fx)
    a = lattice[y0][:, x0]
    b = lattice[y0][:, x0 + 1]
    c = lattice[y0 + 1][:, x0]
    d = lattice[y0 + 1][:, x0 + 1]
    return (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy


def fractal(rng: np.random.Generator, base: int = 4, octaves: int = 5) -> np.ndarray:
    total, amp, norm = np.zeros((H, W)), 1.0, 0.0
    for o in range(octaves):
        total += amp * value_noise(rng, base * 2**o * 4, max(1, base * 2**o))
        norm += amp
        amp *= 0.5
    return total / norm


def mix(t: np.ndarray, c0, c1) -> np.ndarray:
    c0, c1 = np.asarray(c0, float), np.asarray(c1, float)
    return np.clip(c0 + (c1 - c0) * t[..., None], 0, 255)


def wood(rng) -> np.ndarray:
    """Horizontal planks with wavy grain rings."""
    yy, xx = np.mgrid[0:H, 0:W].astype(float)
    warp = fractal(rng, 2, 4) * 6.0
    rings = 0.5 + 0.5 * np.sin((yy / 2.2 + warp * 3.0 + 0.02 * xx))
    grain = rings**3 * 0.7 + fractal(rng, 8, 3) * 0.3
    img = mix(grain, (150, 95, 50), (95, 55, 25))
    plank = (yy % 16) < 1
    seams = ((xx + 97 * (yy // 16)) % 128) < 1.5
    img[plank | seams] *= 0.45
    return img


def stone(rng) -> np.ndarray:
    """Grey stone: fractal noise with darker cracks."""
    n = fractal(rng, 3, 6)
    cracks = np.abs(fractal(rng, 2, 4) - 0.5) < 0.02
    img = mix(n, (95, 95, 100), (190, 188, 180))
    img[cracks] *= 0.4
    return img


def bricks(rng) -> np.ndarray:
    """Red brick courses with light mortar, each brick a slightly different tint."""
    yy, xx = np.mgrid[0:H, 0:W]
    row = yy // 8
    col = (xx + (row % 2) * 8) // 16
    tint = rng.uniform(0.75, 1.15, size=(row.max() + 1, col.max() + 1))[row, col]
    img = np.asarray((165, 60, 45), float)[None, None] * tint[..., None]
    img *= (0.85 + 0.3 * fractal(rng, 8, 3))[..., None]
    mortar = ((yy % 8) == 0) | (((xx + (row % 2) * 8) % 16) == 0)
    img[mortar] = (205, 200, 185)
    return np.clip(img, 0, 255)


def tiles(rng) -> np.ndarray:
    """Teal and cream diamond tiles with a noisy glaze."""
    yy, xx = np.mgrid[0:H, 0:W].astype(float)
    d = (np.abs((xx % 32) - 16) + np.abs((yy % 32) - 16)) < 10
    img = np.where(d[..., None], np.asarray((40, 150, 140), float), np.asarray((235, 225, 195), float))
    img *= (0.85 + 0.3 * fractal(rng, 6, 3))[..., None]
    return np.clip(img, 0, 255)


TEXTURES = {"wall_wood": wood, "wall_stone": stone, "wall_brick": bricks, "wall_tiles": tiles}


def main() -> None:
    OUT.mkdir(exist_ok=True)
    for i, (name, draw) in enumerate(TEXTURES.items()):
        write_png(OUT / f"{name}.png", draw(np.random.default_rng(1234 + i)))
        print("wrote", OUT / f"{name}.png")


if __name__ == "__main__":
    main()
