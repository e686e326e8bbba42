"""The Pareto front of the speed/accuracy bench (the measurements themselves are in the bench)."""

from __future__ import annotations

from seamtrack.bench.tradeoff import cases, pareto


def row(t: float, mx: float, rms: float) -> dict[str, float]:
    return {"total_s": t, "max_error_mm": mx, "rms_error_mm": rms}


def test_a_slower_and_worse_run_is_off_the_front() -> None:
    rows = [row(1.0, 0.02, 0.004), row(2.0, 0.03, 0.005), row(0.5, 0.05, 0.02)]
    assert pareto(rows) == [True, False, True]


def test_differences_within_the_noise_margin_do_not_dominate() -> None:
    """The same numbers 1 % faster (timing noise) leave both on the front."""
    rows = [row(1.00, 0.02, 0.004), row(0.99, 0.02, 0.004)]
    assert pareto(rows) == [True, True]
    rows = [row(1.00, 0.02, 0.004), row(0.80, 0.02, 0.004)]  # 20 % faster: it dominates
    assert pareto(rows) == [False, True]


def test_every_knob_is_turned_from_the_default() -> None:
    labels = [label for label, _ in cases()]
    assert labels[0] == "default" and "fast preview" in labels
    for knob in ("tolerance_mm", "rays", "refine_float64", "frame_rate_hz", "control_period_s"):
        assert any(label.startswith(knob) for label in labels)
