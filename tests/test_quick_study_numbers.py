"""The built-in quick studies give the same numbers as before: the selected structure, the RMSE
and every estimate of the hover and 70 kt cases, against values saved from earlier code.

What reproduces across machines and what does not (measured 2026-11-27): the same code flies
data that differ by 1e-11 relative on another BLAS kernel (tests/test_helisim_turbulence.py),
and the reduction path and the model without delays follow them to 3e-10. The delayed fits do
not: their cost is multi-modal in the delays, and on the quick 70 kt case the four delay starts
end in one minimum on one machine (M_p 0.03 s, M_lat 0.185 s; det R 4.88e-12) and in another on
the next (M_p 0.255 s, M_lat dropped at 0; det R 6.18e-12, though the first is a minimum there
too). So the delayed numbers are compared exactly where the model without delays reproduces
the saved one to round-off (the machine they were saved on, 2026-11-27), and elsewhere by their
RMSE within 1 %."""

import json
from pathlib import Path

import pytest

REFERENCE = json.loads((Path(__file__).parent / "reference" / "quick_study_estimates.json")
                       .read_text(encoding="utf-8"))
#: Agreement of the model without delays that marks the machine the numbers were saved on.
SAME_MACHINE = 1e-12


def _numbers(estimate) -> dict[str, float]:
    return {**{n: p["value"] for n, p in estimate["parameters"].items()},
            **{n: p["value"] for n, p in estimate["delays"].items()}}


def _saved(saved) -> dict[str, float]:
    return {**saved["values"], **saved["delays"]}


def _agree(got, saved, rel) -> bool:
    return got.keys() == saved.keys() and all(
        got[n] == pytest.approx(v, rel=rel, abs=1e-12) for n, v in saved.items())


@pytest.mark.parametrize("case", ["hover", "forward"])
def test_quick_study_estimates_match_the_saved_numbers(quick_study, case):
    result = json.loads((quick_study.out / case / "result.json").read_text(encoding="utf-8"))
    expected = REFERENCE[case]
    assert result["selected_structure"] == expected["selected_structure"]
    assert set(result["estimates"]) == set(expected["estimates"])
    plain, saved_plain = result["estimates"]["no delays"], expected["estimates"]["no delays"]
    assert plain["rmse"] == pytest.approx(saved_plain["rmse"], rel=1e-8)
    assert _agree(_numbers(plain), _saved(saved_plain), rel=1e-6)
    delayed, saved = result["estimates"]["with delays"], expected["estimates"]["with delays"]
    if _agree(_numbers(plain), _saved(saved_plain), rel=SAME_MACHINE):
        assert delayed["rmse"] == pytest.approx(saved["rmse"], rel=1e-9)
        assert _agree(_numbers(delayed), _saved(saved), rel=1e-7)
    else:
        assert delayed["rmse"] == pytest.approx(saved["rmse"], rel=0.01)
