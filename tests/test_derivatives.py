"""Derivative names, sign priors and delays: what is accepted and what is rejected."""

import attrs
import pytest
from rotorid.errors import DerivativeError, RotoridError, StructureError
from rotorid.model.derivatives import Delay, Derivative, Sign, parse_name
from rotorid.model.structure import FlightCondition, ModelStructure


@pytest.mark.parametrize("name, letter, variable", [
    ("X_u", "X", "u"), ("L_p", "L", "p"), ("M_long", "M", "long"), ("N_ped", "N", "ped"),
    ("Z_coll", "Z", "coll"), ("Y_lat", "Y", "lat"),
])
def test_names_split_into_letter_and_variable(name, letter, variable):
    assert parse_name(name) == (letter, variable)
    derivative = Derivative(name)
    assert (derivative.letter, derivative.variable) == (letter, variable)


@pytest.mark.parametrize("name, is_control, equation", [
    ("X_u", False, "u"), ("Y_r", False, "v"), ("Z_w", False, "w"),
    ("L_lat", True, "p"), ("M_long", True, "q"), ("N_ped", True, "r"),
])
def test_the_six_dof_structure_knows_each_derivatives_equation_and_role(name, is_control,
                                                                        equation):
    structure = ModelStructure.six_dof(FlightCondition())
    derivative = structure.derivative(name)
    assert structure.is_control(derivative) is is_control
    assert structure.equation_of(derivative) == equation


@pytest.mark.parametrize("name, fragment", [
    ("Lp", "must look like"),
    ("L_3p", "must look like"),
    ("3_p", "must look like"),
    ("", "must look like"),
    (3, "must look like"),
])
def test_malformed_names_are_rejected_with_the_reason(name, fragment):
    with pytest.raises(DerivativeError, match=fragment):
        Derivative(name)


@pytest.mark.parametrize("name", ["Q_p", "l_p", "L_x", "L_theta", "L_p_q"])
def test_names_the_six_dof_template_lacks_are_rejected_listing_what_it_has(name):
    with pytest.raises(StructureError, match=r"does not fit the six-dof template \(equations "
                                             r"X Y Z L M N; variables u v w p q r long"):
        ModelStructure(FlightCondition(), [Derivative(name)])


def test_defaults_are_free_zero_without_prior_or_delay():
    derivative = Derivative("M_q")
    assert (derivative.initial, derivative.sign, derivative.delay, derivative.fixed) == (
        0.0, Sign.NONE, None, False)


@pytest.mark.parametrize("given, expected", [
    ("negative", Sign.NEGATIVE), ("POSITIVE", Sign.POSITIVE), ("none", Sign.NONE),
    (None, Sign.NONE), (Sign.NEGATIVE, Sign.NEGATIVE),
])
def test_sign_priors_are_parsed(given, expected):
    assert Derivative("L_p", sign=given).sign is expected


def test_unknown_sign_prior_is_rejected():
    with pytest.raises(DerivativeError, match="unknown sign prior 'negatve'"):
        Derivative("L_p", sign="negatve")


@pytest.mark.parametrize("sign, value, admitted", [
    ("negative", -1.0, True), ("negative", 0.0, True), ("negative", 0.5, False),
    ("positive", 2.0, True), ("positive", 0.0, True), ("positive", -0.1, False),
    ("none", -3.0, True), ("none", 3.0, True),
])
def test_sign_prior_admits(sign, value, admitted):
    assert Sign(sign).admits(value) is admitted


def test_initial_value_against_sign_prior_is_rejected():
    with pytest.raises(DerivativeError, match=r"L_p: initial value 0.5 contradicts its negative"):
        Derivative("L_p", initial=0.5, sign="negative")


def test_fixed_value_against_sign_prior_is_rejected():
    with pytest.raises(DerivativeError, match=r"N_v: fixed value -2.0 contradicts its positive"):
        Derivative("N_v", initial=-2.0, sign="positive", fixed=True)
    with pytest.raises(DerivativeError, match="fixed value"):
        Derivative("N_v", sign="positive").fixed_at(-2.0)


@pytest.mark.parametrize("value", [float("nan"), float("inf"), -float("inf")])
def test_non_finite_initial_value_is_rejected(value):
    with pytest.raises(DerivativeError, match="X_u: initial value must be finite"):
        Derivative("X_u", initial=value)


def test_delay_settings():
    delay = Delay(0.05, upper=0.2, fixed=True)
    assert (delay.initial, delay.upper, delay.fixed) == (0.05, 0.2, True)
    assert Delay().initial == 0.0 and Delay().upper is None


@pytest.mark.parametrize("kwargs, fragment", [
    ({"initial": -0.01}, "a delay cannot be negative"),
    ({"initial": 0.3, "upper": 0.2}, "exceeds its upper bound 0.2"),
    ({"upper": 0.0}, "upper bound must be > 0 s"),
    ({"upper": -1.0}, "upper bound must be > 0 s"),
    ({"initial": float("nan")}, "must be finite"),
    ({"upper": float("inf")}, "must be finite"),
])
def test_bad_delays_are_rejected(kwargs, fragment):
    with pytest.raises(DerivativeError, match=fragment):
        Delay(**kwargs)


@pytest.mark.parametrize("value, expected", [
    (None, None), (0.1, Delay(0.1)), ({"initial": 0.1, "upper": 0.3}, Delay(0.1, 0.3)),
    (Delay(0.2, fixed=True), Delay(0.2, fixed=True)),
])
def test_delay_coercion(value, expected):
    assert Derivative("L_lat", delay=value).delay == expected


@pytest.mark.parametrize("value, fragment", [
    ({"initial": 0.1, "maximum": 1}, r"unknown delay setting\(s\) \['maximum'\]"),
    ("0.1", "cannot make a delay"),
    ({"initial": -1.0}, "cannot be negative"),
])
def test_bad_delay_declarations_are_rejected(value, fragment):
    with pytest.raises(DerivativeError, match=fragment):
        Derivative("L_lat", delay=value)


def test_derivatives_are_frozen_and_copies_leave_the_original_alone():
    derivative = Derivative("M_long", initial=1.0)
    with pytest.raises(attrs.exceptions.FrozenInstanceError):
        derivative.initial = 2.0
    delayed = derivative.with_delay(0.04, upper=0.1)
    fixed = derivative.fixed_at(3.0)
    assert derivative.delay is None and not derivative.fixed and derivative.initial == 1.0
    assert delayed.delay == Delay(0.04, 0.1) and delayed.delay_name == "tau_M_long"
    assert fixed.fixed and fixed.initial == 3.0


def test_derivative_errors_are_rotorid_value_errors():
    with pytest.raises(RotoridError):
        Derivative("Au")
    with pytest.raises(ValueError):
        Derivative("Au")


@pytest.mark.parametrize("value", ["1.0", True, None, [1.0]])
def test_values_that_are_not_numbers_are_rejected(value):
    with pytest.raises(DerivativeError, match="must be real numbers"):
        Derivative("L_p", initial=value)
    with pytest.raises(DerivativeError, match="must be real numbers"):
        Delay(initial=value)
