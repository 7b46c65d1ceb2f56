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
