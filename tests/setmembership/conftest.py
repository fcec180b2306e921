"""Fixtures of the SMFDO tests."""

from __future__ import annotations

import pytest

from setobs.setmembership import _closed_form


@pytest.fixture
def exact_window_lps(monkeypatch):
    """The window's hull LPs solved to their optimum (no early stop,
    ``_closed_form.WINDOW_REL_GAP = 0``): for tests that compare the fast path with the
    reference path's exact LPs to rounding. The default's early stop is tested in
    ``test_smfdo_fast.py`` (``test_the_window_lps_early_stop_is_outward_and_small``)."""
    monkeypatch.setattr(_closed_form, "WINDOW_REL_GAP", 0.0)
