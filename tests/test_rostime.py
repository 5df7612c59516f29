"""ROS Time and Duration: normalisation, conversions and arithmetic as in genpy."""

from __future__ import annotations

import math

import pytest

from duckielib.rostime import Duration, Time


def test_normalisation_and_conversions():
    t = Time(1, 2_500_000_000)
    assert (t.secs, t.nsecs) == (3, 500_000_000)
    assert t.to_sec() == 3.5
    assert t.to_nsec() == 3_500_000_000
    assert Time.from_sec(1.25) == Time(1, 250_000_000)
    assert Time.from_nsec(1_000_000_001) == Time(1, 1)
    assert Duration.from_sec(0.1).nsecs == 100_000_000


def test_negative_durations_keep_nanoseconds_positive():
    d = Duration(-0.5)
    assert (d.secs, d.nsecs) == (-1, 500_000_000)
    assert d.to_sec() == -0.5
    assert -Duration(2) == Duration(-2)
    assert abs(Duration(-3)) == Duration(3)


def test_arithmetic():
    start, later = Time(10), Time(12, 500_000_000)
    assert later - start == Duration(2.5)
    assert start + Duration(2.5) == later
    assert Duration(2.5) + start == later
    assert later - Duration(2.5) == start
    assert Duration(1.5) * 2 == Duration(3)
    assert Duration(3) / 2 == Duration(1.5)
    assert Duration(3) / Duration(1.5) == 2.0
    assert Duration(3) // Duration(2) == 1
    assert Duration(1) - Duration(3) == Duration(-2)


def test_comparison_and_zero():
    assert Time(1) < Time(1, 1) <= Time(1, 1) < Time(2)
    assert Time(0).is_zero()
    assert not Time(0)
    assert Duration(0.001)
    assert Time(1) != Duration(1)
    assert len({Time(1), Time(1, 0), Time(2)}) == 2
    with pytest.raises(TypeError):
        _ = Time(1) < Duration(1)


def test_time_plus_time_is_a_mistake():
    with pytest.raises(TypeError):
        _ = Time(1) + Time(2)


@pytest.mark.parametrize("value", [math.nan, math.inf])
def test_non_finite_seconds_are_refused(value):
    with pytest.raises(ValueError, match="cannot hold"):
        Duration(value)


def test_negative_time_is_refused():
    with pytest.raises(ValueError, match="Time cannot be negative"):
        Time(-1)
    with pytest.raises(ValueError, match="Time cannot be negative"):
        _ = Time(1) - Duration(2)


def test_text_is_refused():
    with pytest.raises(TypeError, match="numbers of seconds and nanoseconds"):
        Time("now")
