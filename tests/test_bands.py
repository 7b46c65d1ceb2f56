"""Row bands on a thread pool (ibr.render.bands): every row done once, errors raised."""

from __future__ import annotations

import numpy as np
import pytest

from ibr.render.bands import run_bands, thread_count


def _fill_rows(start, stop, out, calls):
    calls.append((start, stop))
    out[start:stop] += np.arange(start, stop)[:, None]


@pytest.mark.parametrize("n", [1, 7, 16, 33, 1000])
def test_every_row_once_in_contiguous_pieces(n):
    out, calls = np.zeros((n, 3)), []
    run_bands(_fill_rows, n, out, calls, min_rows=4)
    np.testing.assert_array_equal(out, np.repeat(np.arange(n)[:, None], 3, 1))  # each row written exactly once
    calls.sort()
    assert calls[0][0] == 0 and calls[-1][1] == n and all(a[1] == b[0] for a, b in zip(calls, calls[1:]))
    assert len(calls) == max(1, min(thread_count(), n // 4))


def test_an_error_in_any_piece_is_raised():
    def kernel(start, stop):
        if start > 0 or thread_count() == 1:
            raise ValueError(f"rows {start}..{stop}")

    with pytest.raises(ValueError, match="rows"):
        run_bands(kernel, 100)


@pytest.mark.parametrize("nquads, height, nbands", [(0, 10, 4), (1, 1, 1), (300, 97, 8), (2000, 1080, 8), (50, 5, 5)])
def test_bucket_bands_lists_each_visible_quad_in_every_band_it_touches_in_quad_order(nquads, height, nbands):
    from ibr.render._raster_kernels import bucket_bands

    rng = np.random.default_rng(nquads + height)
    v0 = rng.integers(0, height, nquads)
    v1 = np.minimum(height - 1, v0 + rng.integers(0, height // 2 + 1, nquads))
    u0 = rng.integers(0, 50, nquads)
    u1 = u0 + rng.integers(-1, 20, nquads)  # some empty in u
    v1[::5] = v0[::5] - 1  # some empty in v (the rasterizer's "not visible")
    bbox = np.stack([u0, v0, u1, v1], 1).astype(np.int32)
    start, quads = bucket_bands(bbox, height, nbands)
    rows = -(-height // nbands)
    expected = [[q for q in range(nquads) if u0[q] <= u1[q] and v0[q] <= v1[q] and v0[q] // rows <= k <= v1[q] // rows]
                for k in range(nbands)]
    assert start.dtype == np.int64 and quads.dtype == np.int32 and len(start) == nbands + 1 and start[0] == 0
    assert [quads[start[k]:start[k + 1]].tolist() for k in range(nbands)] == expected
