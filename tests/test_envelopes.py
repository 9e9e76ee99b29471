"""MUAD, AEE-table and mismatch-cost envelopes against published and hand-computed values."""

from importlib.metadata import entry_points

import numpy as np
import pytest
import rotorid_envelopes.plugin as envelope_plugin
from rotorid.errors import VerificationError
from rotorid.plugin.manager import create, new_plugin_manager, registry
from rotorid.plugin.contracts import ValidationEnvelope
from rotorid.verification.envelopes import wrap180

# reference/validation.md §1.4: ω, mag upper, mag lower, phase upper (no delay, delay),
# phase lower (no delay, delay).
MUAD_TABLE = np.array([
    [0.1, 16.93, -6.62, 136.45, 136.48, -56.57, -56.61],
    [0.2, 12.29, -5.38, 102.88, 102.95, -38.67, -38.75],
    [0.3, 9.34, -4.25, 80.02, 80.12, -28.87, -29.00],
    [0.5, 5.94, -2.82, 54.00, 54.17, -19.75, -19.96],
    [1.0, 2.74, -1.65, 30.05, 30.39, -13.66, -14.07],
    [2.0, 1.43, -1.33, 18.34, 19.02, -13.92, -14.75],
    [3.0, 1.31, -1.41, 15.65, 16.66, -16.98, -18.22],
    [5.0, 1.72, -1.85, 15.66, 17.35, -24.27, -26.33],
    [7.0, 2.39, -2.47, 17.42, 19.79, -31.23, -34.12],
    [10.0, 3.49, -3.57, 20.37, 23.75, -40.04, -44.17],
    [20.0, 6.32, -7.13, 25.65, 32.41, -57.26, -65.51],
])
# reference/validation.md §3.1: W_γ at γ² = 0.5 … 1.0.
COHERENCE_WEIGHTS = {0.5: 0.386, 0.6: 0.508, 0.7: 0.633, 0.8: 0.757, 0.9: 0.879, 1.0: 0.998}


@pytest.fixture(scope="module")
def manager():
    return new_plugin_manager([envelope_plugin], load_entry_points=False)


def envelope(manager, name, **options):
    return create("validation-envelopes", name, manager, **options)


def test_registered_through_entry_point_and_hook(manager):
    group = entry_points(group="rotorid")
    assert "rotorid_envelopes.plugin" in {e.value for e in group if e.name == "envelopes"}
    assert list(registry("validation-envelopes", manager)) == ["aee", "mismatch-cost", "muad"]
    for name in ("aee", "mismatch-cost", "muad"):
        assert isinstance(envelope(manager, name), ValidationEnvelope)


def test_muad_reproduces_published_table(manager):
    omega = MUAD_TABLE[:, 0]
    with_delay = envelope(manager, "muad").bounds(omega)
    without = envelope(manager, "muad", delay_terms=False).bounds(omega)
    assert np.allclose(with_delay.mag_upper_db, MUAD_TABLE[:, 1], atol=0.02)
    assert np.allclose(with_delay.mag_lower_db, MUAD_TABLE[:, 2], atol=0.02)
    assert np.allclose(without.phase_upper_deg, MUAD_TABLE[:, 3], atol=0.02)
    assert np.allclose(with_delay.phase_upper_deg, MUAD_TABLE[:, 4], atol=0.02)
    assert np.allclose(without.phase_lower_deg, MUAD_TABLE[:, 5], atol=0.02)
    assert np.allclose(with_delay.phase_lower_deg, MUAD_TABLE[:, 6], atol=0.02)
    assert with_delay.extrapolated.tolist() == [False] * 10 + [True]


def test_muad_phase_branch_and_tightest_region(manager):
    omega = np.geomspace(0.1, 10.0, 2000)
    bounds = envelope(manager, "muad", delay_terms=False).bounds(omega)
    assert np.all(bounds.phase_upper_deg > 0)  # negative DC gain, yet never shifted by 360°
    low = np.argmin(bounds.phase_upper_deg)
    assert omega[low] == pytest.approx(3.9, abs=0.15)
    assert bounds.phase_upper_deg[low] == pytest.approx(15.2, abs=0.05)
    upper = envelope(manager, "muad").bounds(omega)
    assert np.min(upper.mag_upper_db) == pytest.approx(1.30, abs=0.01)
    assert omega[np.argmin(upper.mag_upper_db)] == pytest.approx(2.8, abs=0.1)
    assert np.max(upper.mag_lower_db) == pytest.approx(-1.33, abs=0.01)
    # a single evaluation point far from 0.1 rad/s gets the same branch
    assert envelope(manager, "muad").bounds([7.0]).phase_upper_deg[0] == pytest.approx(
        19.79, abs=0.02)


def test_muad_check_flags_missing_delay(manager):
    muad = envelope(manager, "muad")
    omega = np.geomspace(0.2, 12.0, 80)
    coherence = np.ones_like(omega)
    perfect = muad.check(np.ones_like(omega, dtype=complex), coherence, omega)
    assert perfect.passed is True and perfect.status == "pass"
    assert perfect.n_used == int(np.sum(omega <= 10.0))  # 10–12 rad/s extrapolated
    missing = muad.check(np.exp(0.08j * omega), coherence, omega)  # model lacks a 0.08 s delay
    assert missing.passed is False and missing.status == "fail"
    failing = omega[missing.used & ~missing.inside]
    assert failing.min() > 3.0 and failing.max() <= 10.0
    last = omega[omega <= 10.0].max()  # the phase error grows fastest there
    assert missing.worst_margin_deg == pytest.approx(
        muad.bounds([last]).phase_upper_deg[0] - np.degrees(0.08 * last), abs=1e-6)
    # the failing points do not count when their coherence is low
    weak = np.where(omega > 3.0, 0.5, 1.0)
    assert muad.check(np.exp(0.08j * omega), weak, omega).passed is True
    nothing = muad.check(np.ones(3), np.full(3, 0.2), np.array([1.0, 2.0, 3.0]))
    assert nothing.passed is None and nothing.status == "no coherent points"
    assert "lower the envelope's threshold" in nothing.report()
    with pytest.raises(VerificationError, match="one length"):
        muad.check(np.ones(3), np.ones(4), np.ones(3))


def test_packaged_aee_is_unverified_and_empty(manager):
    aee = envelope(manager, "aee")
    assert aee.verified is False and "AVT-296" in aee.provenance
    check = aee.check(np.ones(5), np.ones(5), np.geomspace(1.0, 5.0, 5))
    assert check.passed is None and check.status == "not available"
    assert np.all(np.isnan(aee.bounds([1.0]).mag_upper_db))
    assert check.report().startswith("AEE: not available, no point checked [UNVERIFIED source")
    assert "nan" not in check.report()


def _write_table(path, verified="false", provenance='"transcribed test table"',
                 mag_upper="[[0.1, 3.0], [10.0, 5.0]]"):
    path.write_text(f"""
name = "AEE-test"
provenance = {provenance}
verified = {verified}
omega_range = [0.1, 10.0]
mag_upper = {mag_upper}
mag_lower = [[0.1, -3.0], [10.0, -5.0]]
phase_upper = [[0.1, 20.0], [1.0, 10.0], [10.0, 30.0]]
phase_lower = [[0.1, -20.0], [10.0, -30.0]]
""", encoding="utf-8")
    return path


def test_user_table_interpolates_in_log_omega(manager, tmp_path):
    table = envelope(manager, "aee", path=_write_table(tmp_path / "aee.toml"))
    bounds = table.bounds([1.0, np.sqrt(10.0), 20.0])
    assert bounds.mag_upper_db[:2] == pytest.approx([4.0, 4.5])  # linear in log10 ω
    assert bounds.phase_upper_deg[:2] == pytest.approx([10.0, 20.0])
    assert bounds.extrapolated.tolist() == [False, False, True]
    assert np.isnan(bounds.mag_upper_db[2])
    check = table.check(np.full(3, 10 ** (4.2 / 20)), np.ones(3), np.array([1.0, 3.0, 20.0]))
    assert check.inside[:2].tolist() == [False, True] and not check.used[2]
    assert check.status == "fail (unverified envelope)"
    passing = table.check(np.ones(2), np.ones(2), np.array([1.0, 3.0]))
    assert passing.status == "pass (unverified envelope)"


@pytest.mark.parametrize("change, message", [
    (dict(provenance='""'), "provenance"),
    (dict(verified='"yes"'), "verified"),
    (dict(mag_upper="[[1.0, 3.0], [0.5, 5.0]]"), "increase"),
    (dict(mag_upper="[[0.5, 3.0], [10.0, 5.0]]"), "cover omega_range"),
    (dict(mag_upper="[]"), "all four"),
])
def test_bad_tables_are_rejected(manager, tmp_path, change, message):
    path = _write_table(tmp_path / "bad.toml", **change)
    with pytest.raises(VerificationError, match=message):
        envelope(manager, "aee", path=path)


def test_coherence_weight_matches_published_values():
    from rotorid_envelopes.cost import coherence_weight

    for coherence, weight in COHERENCE_WEIGHTS.items():
        assert coherence_weight(coherence) == pytest.approx(weight, abs=6e-4)


def test_mismatch_cost_hand_computed_cases(manager):
    cost = envelope(manager, "mismatch-cost")
    omega = np.geomspace(0.5, 10.0, 100)
    ones = np.ones_like(omega)
    # uniform 2.24 dB error at γ² = 1: J = 20 · W_γ(1) · 2.24² ≈ 100
    result = cost.check(np.full(omega.shape, 10 ** (2.24 / 20)), ones, omega)
    assert result.cost == pytest.approx(20 * 0.998 * 2.24 ** 2, rel=1e-3)
    assert result.cost == pytest.approx(100.0, abs=0.5)
    assert result.omega.size == 20 and result.omega[0] == pytest.approx(0.5)
    # uniform 16.9° phase error alone gives J ≈ 100 as well (validation.md §3.2)
    phase_only = cost.check(np.exp(1j * np.radians(16.9)) * ones, ones, omega)
    assert phase_only.cost == pytest.approx(20 * 0.998 * 0.01745 * 16.9 ** 2, rel=1e-3)
    assert phase_only.cost == pytest.approx(100.0, abs=1.0)
    # 1 dB and −10° together at γ² = 0.8: 20 · 0.757 · (1 + 0.01745 · 100)
    mixed = cost.check(10 ** (1 / 20) * np.exp(-1j * np.radians(10.0)) * ones, 0.8 * ones,
                       omega)
    assert mixed.cost == pytest.approx(20 * 0.757 * (1 + 1.745), rel=1e-3)
    assert mixed.passed is True
    assert cost.check(ones.astype(complex), ones, omega).cost == pytest.approx(0.0, abs=1e-12)


def test_mismatch_cost_uses_the_coherent_range(manager):
    cost = envelope(manager, "mismatch-cost")
    omega = np.geomspace(0.1, 20.0, 200)
    coherence = np.where((omega >= 1.0) & (omega <= 8.0), 0.95, 0.3)
    # huge errors outside the coherent range must not count
    error = np.where(coherence > 0.5, 10 ** (1 / 20), 100.0).astype(complex)
    result = cost.check(error, coherence, omega)
    assert result.omega.min() >= 1.0 and result.omega.max() <= 8.0
    assert result.cost == pytest.approx(20 * (1.58 * (1 - np.exp(-0.95))) ** 2, rel=1e-3)
    empty = cost.check(error, np.full_like(omega, 0.1), omega)
    assert empty.cost is None and empty.status == "no coherent points"


def test_wrap180():
    assert wrap180([180.0, -180.0, 190.0, -190.0, 540.0]).tolist() == [
        180.0, 180.0, -170.0, 170.0, 180.0]


def test_a_check_says_where_its_points_fall_outside(manager):
    muad = envelope(manager, "muad")
    omega = np.array([0.5, 1.0, 2.0, 4.0])
    inside = muad.check(np.ones(4, complex), np.ones(4), omega)
    assert inside.outside_text() == ""
    error = np.array([1.0, 1.0, 10.0, 10.0], complex)        # +20 dB at 2 and 4 rad/s
    outside = muad.check(error, np.ones(4), omega)
    assert outside.outside_text() == "; outside at 2–4 rad/s"
