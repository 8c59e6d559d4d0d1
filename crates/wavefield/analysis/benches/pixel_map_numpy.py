"""Independent NumPy implementation of the pixel-area map's focal fields (benches/pixel_map.rs), timed on the same G.

Usage: PIXEL_MAP_EXPORT=/tmp/G.bin cargo bench -p metaplate-analysis --bench pixel_map   (writes G once)
       python3 wavefield/analysis/benches/pixel_map_numpy.py /tmp/G.bin

For each target point j (single-pixel inverse filter, closed form, relative Tikhonov 0.01) the field at focus time at
every point i is  v_i = sum_k (c_k / N) w_k / (|g_jk|^2 (1 + 0.01^2)) Re(G_ik . conj(g_jk)),  computed here as one
complex matrix product per bin accumulated over bins (no Re/Im stacking, unlike the Rust GEMM), then checked against
the Rust map's peaks (the field at each target). Areas are not recomputed (marching squares is the Rust side's);
the check of the focal fields is what makes this an independent implementation of the dominant cost.
"""

import math
import sys
import time

import numpy as np


def load(path):
    raw = open(path, "rb").read()
    bins, points, actuators, fft_len = np.frombuffer(raw, "<u8", 4, 0)
    bins, points, actuators, fft_len = int(bins), int(points), int(actuators), int(fft_len)
    off = 32
    fs = float(np.frombuffer(raw, "<f8", 1, off)[0])
    off += 8
    gains = np.frombuffer(raw, "<f8", bins, off)
    off += 8 * bins
    g = np.frombuffer(raw, "<c16", bins * points * actuators, off).reshape(bins, actuators, points)
    off += 16 * bins * points * actuators
    peaks = np.frombuffer(raw, "<f8", points, off)
    off += 8 * points
    areas = np.frombuffer(raw, "<f8", points, off)
    # Column-major per bin: (bins, actuators, points) -> (bins, points, actuators).
    return np.ascontiguousarray(g.transpose(0, 2, 1)), gains, fft_len, fs, peaks, areas


def focal_fields(g, gains, fft_len, first_bin, alpha_rel=0.01):
    bins, points, _ = g.shape
    out = np.zeros((points, points))
    for k in range(bins):
        gk = g[k]
        edge = first_bin + k == 0 or 2 * (first_bin + k) == fft_len
        weight = (1.0 if edge else 2.0) * gains[k] / fft_len
        norm = np.einsum("ij,ij->i", gk.real, gk.real) + np.einsum("ij,ij->i", gk.imag, gk.imag)
        scale = np.where(norm > 0, weight / (norm * (1.0 + alpha_rel**2)), 0.0)
        # Row t of the result: targets; column i: points. Re(G_i . conj(g_t)).
        out += (scale[:, None] * (gk.conj() @ gk.T)).real
    return out


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "/tmp/pixel_map_G.bin"
    g, gains, fft_len, fs, peaks, areas = load(path)
    bins, points, actuators = g.shape
    first_bin = math.ceil(75.0 / (fs / fft_len))  # as band_bins: the first bin at or above 75 Hz
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        f = focal_fields(g, gains, fft_len, first_bin)
        times.append(time.perf_counter() - t0)
    flops = 8.0 * bins * points * points * actuators  # complex GEMM: 8 real flops per complex multiply-add
    best = min(times)
    err = np.max(np.abs(np.diag(f) - peaks)) / np.max(np.abs(peaks))
    print(f"numpy {np.__version__}: {points} points x {actuators} actuators x {bins} bins")
    print(f"focal fields: best {best * 1e3:.1f} ms, median {np.median(times) * 1e3:.1f} ms over {len(times)} runs; "
          f"{flops / 1e9:.2f} GFlop as complex GEMMs ({flops / best / 1e9:.1f} GFlop/s)")
    print(f"max |peak(numpy) - peak(rust)| / max peak = {err:.2e}")
    print(f"Rust map: median area {np.nanmedian(areas):.2f} cm^2, {np.isnan(areas).sum()} of {points} flagged")
    for sub in (points // 4, points // 2):
        rows = (np.arange(sub) * points) // sub
        t0 = time.perf_counter()
        focal_fields(np.ascontiguousarray(g[:, rows, :]), gains, fft_len, first_bin)
        print(f"  {sub} points: {(time.perf_counter() - t0) * 1e3:.1f} ms")
    half = bins // 2
    t0 = time.perf_counter()
    focal_fields(np.ascontiguousarray(g[:half]), gains[:half], fft_len, first_bin)
    print(f"  half band ({half} bins), {points} points: {(time.perf_counter() - t0) * 1e3:.1f} ms")


if __name__ == "__main__":
    main()
