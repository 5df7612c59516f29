"""The notebooks' claims: sentences that say what a figure or a printout shows, and their checks.

A notebook's text tells the student what to see in a figure or a table ("the trim straightens
the robot", "the count goes up while the robot rolls back"). Each such sentence is a claim, and
the simulator can drift away from it (a refit robot, a new seed). Every claim is listed here
with the words that make it and the numbers that back it: the notebook prints them, and the
claim holds when the printed numbers satisfy it. The gates in ``test_course_run_all.py`` check
every claim on the runs they already make (the source notebooks and the release filled with
the reference answers), so a change to the text, the cells or the simulator that breaks a
claim fails there, naming the sentence and the numbers.

To add a claim: make the cell that draws the figure print the numbers the sentence is about
(students read them too), then list the claim in ``CLAIMS`` under its notebook.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Callable, Dict, List, Mapping, Optional, Union

__all__ = ["CLAIMS", "Claim", "check_claim", "markdown_text"]


@dataclass(frozen=True)
class Claim:
    """A sentence of a notebook about its own figures or printouts, and the numbers behind it.

    Attributes:
        says: words of the notebook's markdown that make the claim, as written (spaces and
            line breaks may differ).
        printed: a regular expression with named groups, searched in everything the notebook's
            code cells printed; each group is read as a number (as text if it is none).
        holds: called with the groups' numbers as keyword arguments; true when the claim holds.
        meaning: the claim in a few words, for the failure message.
    """

    says: str
    printed: str
    holds: Callable[..., bool]
    meaning: str


def _words(text: str) -> str:
    return " ".join(text.split())


def markdown_text(notebook: Mapping[str, object]) -> str:
    """All the markdown of a notebook, its spaces and line breaks made single spaces."""
    cells = notebook.get("cells", [])
    parts = []
    for cell in cells:  # type: ignore[attr-defined]
        if cell.get("cell_type") == "markdown":
            text = cell.get("source", "")
            parts.append("".join(text) if isinstance(text, list) else text)
    return _words("\n".join(parts))


def _number(text: str) -> Union[float, str]:
    try:
        return float(text)
    except ValueError:
        return text


def check_claim(claim: Claim, markdown: str, printed: str) -> Optional[str]:
    """Why ``claim`` does not hold in a notebook's text and printouts, or None when it holds."""
    if _words(claim.says) not in _words(markdown):
        return f"the text no longer says {claim.says!r}: update or remove its claim"
    found = re.search(claim.printed, printed)
    if found is None:
        return f"nothing printed matches {claim.printed!r}, the numbers behind {claim.says!r}"
    numbers = {name: _number(value) for name, value in found.groupdict().items()}
    if not claim.holds(**numbers):
        shown = ", ".join(
            f"{name} = {value:g}" if isinstance(value, float) else f"{name} = {value!r}"
            for name, value in numbers.items()
        )
        return f"{claim.says!r} ({claim.meaning}) does not hold: {shown}"
    return None


#: Every notebook's claims, by notebook name.
CLAIMS: Dict[str, List[Claim]] = {}


_NUMBER = r"[-+]?\d+(?:\.\d*)?"

CLAIMS["03_frames"] = [
    Claim(
        says=r"forward $(1, 0)$ must become world $(0, 1)$ and left $(0, 1)$ must become world "
        r"$(-1, 0)$",
        printed=rf"forward \(1, 0\) in the world: \[\s*(?P<fx>{_NUMBER})\s+(?P<fy>{_NUMBER})\]\s*"
        rf"left\s+\(0, 1\) in the world: \[\s*(?P<lx>{_NUMBER})\s+(?P<ly>{_NUMBER})\]",
        holds=lambda fx, fy, lx, ly: (fx, fy, lx, ly) == (0, 1, -1, 0),
        meaning="R(pi/2) turns forward into world +y and left into world -x",
    ),
    Claim(
        says="The two should lie on top of the ground truth (up to the motors' small lag behind "
        "the command).",
        printed=rf"differ by at most (?P<gap>{_NUMBER}) rad",
        holds=lambda gap: gap < 0.1,
        meaning="wrap_angle of the added-up turn stays within 0.1 rad of the simulator's heading",
    ),
    Claim(
        says="*What to look for:* the solid blue line at the moments it meets 0.",
        printed=rf"jumps from about 0 to just below 2π at t = (?P<first>{_NUMBER}) s, "
        rf"(?P<second>{_NUMBER}) s",
        holds=lambda first, second: 0 < first < second <= 12.5,
        meaning="the simulator's heading wraps from 0 to 2*pi during the run, twice",
    ),
]

CLAIMS["04_kinematics"] = [
    Claim(
        says="put the true wheel speeds through your function: it should give the true "
        r"$(v, \omega)$.",
        printed=rf"your forward kinematics: v = (?P<v>{_NUMBER}) m/s, omega = (?P<w>{_NUMBER}) "
        rf"rad/s\s+the simulator's truth:\s+v = (?P<tv>{_NUMBER}) m/s, omega = (?P<tw>{_NUMBER})",
        holds=lambda v, w, tv, tw: abs(v - tv) < 1e-3 and abs(w - tw) < 1e-3 and w > 0,
        meaning="forward kinematics of the true wheel speeds gives the true (v, omega)",
    ),
    Claim(
        says=r"$(v, \omega) = (0.3, 0)$ gives both wheels $0.3 / 0.0318 \approx 9.43$ rad/s",
        printed=rf"\(v, omega\) = \(\s*0\.30,\s*0\.00\) -> wheels \(\s*(?P<left>{_NUMBER}),\s*"
        rf"(?P<right>{_NUMBER})\)",
        holds=lambda left, right: abs(left - 9.43) < 0.01 and abs(right - 9.43) < 0.01,
        meaning="inverse kinematics of (0.3, 0) is 9.43 rad/s on both wheels",
    ),
    Claim(
        says="the wheels do not turn at all below duty 0.12",
        printed=rf"the realistic wheel starts turning at u = (?P<u>{_NUMBER})",
        holds=lambda u: 0.115 <= u <= 0.125,
        meaning="the realistic motor's dead band ends at duty 0.12",
    ),
    Claim(
        says="above it they turn at about half the speed $k$ promises",
        printed=rf"at u = 0\.3: the realistic wheel turns at (?P<s3>{_NUMBER}) rad/s, the model "
        rf"k u promises (?P<m3>{_NUMBER}) rad/s\s+at u = 0\.5: the realistic wheel turns at "
        rf"(?P<s5>{_NUMBER}) rad/s, the model k u promises (?P<m5>{_NUMBER})",
        holds=lambda s3, m3, s5, m5: 0.35 < s3 / m3 < 0.7 and 0.35 < s5 / m5 < 0.7,
        meaning="the realistic wheel turns at 35 to 70 % of k u",
    ),
    Claim(
        says="Your `duty_cycles` with the robot's parameters should give the same numbers.",
        printed=rf"vel_left = (?P<a>{_NUMBER}), vel_right = (?P<b>{_NUMBER})\s+your duty_cycles "
        rf"gives:\s+u_left\s+= (?P<c>{_NUMBER}), u_right\s+= (?P<d>{_NUMBER})",
        holds=lambda a, b, c, d: abs(a - c) < 1e-4 and abs(b - d) < 1e-4,
        meaning="duty_cycles matches what the kinematics node sent",
    ),
    Claim(
        says="It curves to the right: the weaker right wheel is slower.",
        printed=rf"trim 0: travelled {_NUMBER} m and turned (?P<turned>{_NUMBER}) degrees; "
        rf"drifted (?P<drift>{_NUMBER}) m",
        holds=lambda turned, drift: turned < -1 and drift > 0.01,
        meaning="with trim 0 the realistic robot turns clockwise and drifts to its right",
    ),
    Claim(
        says=r"with the robot's own gain (2 on the realistic robot)",
        printed=rf"first guess, -gain \* e with gain (?P<gain>{_NUMBER}):",
        holds=lambda gain: gain == 2,
        meaning="the calibration uses the realistic robot's gain, 2",
    ),
    Claim(
        says=r"A trim changes its turn much less than that formula assumes, so "
        r"$-\text{gain} \cdot e$ is only a first guess, far too small.",
        printed=rf"trim (?P<guess>{_NUMBER}); it turned (?P<turn1>{_NUMBER}) degrees instead of "
        rf"(?P<turn0>{_NUMBER})\s+calibrated trim: (?P<trim>{_NUMBER})",
        holds=lambda guess, turn1, turn0, trim: (
            abs(turn1 - turn0) < 0.5 * abs(turn0) and trim > 3 * guess > 0
        ),
        meaning="the first guess removes less than half of the turn; the calibrated trim is "
        "more than 3 times the first guess",
    ),
    Claim(
        says="with the calibrated trim, the green path drifts far less",
        printed=rf"trim 0: ends at .*\(drift (?P<before>{_NUMBER}) m\).*\s+trim {_NUMBER}: "
        rf"ends at .*\(drift (?P<after>{_NUMBER}) m\)",
        holds=lambda before, after: before > 0.01 and abs(after) < before / 2,
        meaning="the calibrated trim at least halves the drift",
    ),
    Claim(
        says="Trim evens out unequal wheels",
        printed=rf"trim 0: ends at .*turned (?P<before>{_NUMBER}) degrees\s+trim {_NUMBER}: "
        rf"ends at .*turned (?P<after>{_NUMBER}) degrees",
        holds=lambda before, after: before < -1 and abs(after) < abs(before) / 2,
        meaning="the calibrated trim at least halves the turn of a straight run",
    ),
    Claim(
        says="In the simulator the way back retraces the way out (its motors behave the same in "
        "both directions), so the two legs' errors cancel",
        printed=rf"every run ended within (?P<back>{_NUMBER}) m of its start",
        holds=lambda back: back < 0.01,
        meaning="every straight-line run ends within 1 cm of its start",
    ),
    Claim(
        says="Open-loop driving never lands exactly on the goal, and at a poor speed far from it",
        printed=rf"missed 1\.25 m by (?P<best>{_NUMBER}) m at best, (?P<worst>{_NUMBER}) m at "
        "worst",
        holds=lambda best, worst: best > 0 and worst > 0.5,
        meaning="every forward leg misses 1.25 m, the worst by more than 0.5 m",
    ),
    Claim(
        says="a real motor does not turn at all below its dead band",
        printed=rf"realistic\s+0\.03\s+(?P<duty>{_NUMBER})\s+(?P<forward>{_NUMBER})",
        holds=lambda duty, forward: duty < 0.12 and forward == 0,
        meaning="the realistic robot at 0.03 m/s (duty below 0.12) does not move",
    ),
    Claim(
        says='"Heading now minus heading at the start" is then about +266° for a turn of about',
        printed=rf"ideal, first turn: angle travelled (?P<turned>{_NUMBER}) degrees \(asked: "
        rf"-90\.0\); heading now minus heading at the start (?P<difference>{_NUMBER}) degrees",
        holds=lambda turned, difference: (
            -98 < turned < -90 and abs(difference - (turned + 360)) < 0.2
        ),
        meaning="the ideal robot turns past theta = 0, so the heading difference is 360 too large",
    ),
    Claim(
        says="The realistic robot stops short of $\\theta = 0$, so for it the two numbers agree",
        printed=rf"realistic, first turn: angle travelled (?P<turned>{_NUMBER}) degrees \(asked: "
        rf"-90\.0\); heading now minus heading at the start (?P<difference>{_NUMBER}) degrees",
        holds=lambda turned, difference: -90 < turned < -60 and abs(difference - turned) < 0.2,
        meaning="the realistic robot turns less than 90 degrees and its heading does not wrap",
    ),
    Claim(
        says="The node can only stop at one of its 20 Hz ticks, a little after the time asked",
        printed=rf"asked for (?P<asked>{_NUMBER}) s, held for (?P<held>{_NUMBER}) s",
        holds=lambda asked, held: asked < held < asked + 0.05,
        meaning="each turn is held for whole 20 Hz ticks, a little longer than asked",
    ),
    Claim(
        says="the realistic robot's wheels and track are not the ones the node computes with",
        printed=rf"true wheel radius and track: (?P<radius>{_NUMBER}) and (?P<track>{_NUMBER}) "
        "times",
        holds=lambda radius, track: radius < 1 < track,
        meaning="the realistic robot's wheels are smaller and its track wider than the nominal",
    ),
]


def _encoder_counts_05(wheel: str) -> str:
    return (
        rf"{wheel}: (?P<{wheel}_forward>{_NUMBER}) at v = 0\.2, {_NUMBER} at v = 0\.0, "
        rf"(?P<{wheel}_backward>{_NUMBER}) at v = -0\.2, (?P<{wheel}_end>{_NUMBER}) at v = 0\.0"
    )


def _seed_row_05(seed: int) -> str:
    return (
        rf"\s+{seed}\s+(?P<apart{seed}>{_NUMBER}) ms\s+(?P<gap{seed}>{_NUMBER}) cm\s+"
        rf"(?P<most{seed}>{_NUMBER}) deg\s+(?P<end{seed}>{_NUMBER}) deg"
    )


def _back_and_forth_05(run: str, key: str) -> str:
    return "".join(
        rf"\s*{run}\s+{noise}\s+(?P<{key}_{noise}_really>{_NUMBER})\s+"
        rf"(?P<{key}_{noise}_says>{_NUMBER})\s+(?P<{key}_{noise}_off>{_NUMBER})"
        for noise in ("ideal", "realistic")
    )


_MISSION_GAPS_05 = (
    rf"ideal: odometry .*?: (?P<ideal>{_NUMBER}) cm and .*\s+realistic: odometry .*?: "
    rf"(?P<realistic>{_NUMBER}) cm and .*\s+the realistic robot ended (?P<apart>{_NUMBER}) cm"
)
_BACK_AND_FORTH_05 = (
    _back_and_forth_05(r"slow, 0\.15 m/s", "slow")
    + _back_and_forth_05(r"gentle, 0\.3 m/s", "gentle")
    + _back_and_forth_05(r"hard, 0\.8 m/s", "hard")
)
_LAPS_05 = (
    r"realistic: position gap at the end of each side \(cm\):"
    + "".join(rf"\s+(?P<side{k}>{_NUMBER})" for k in range(1, 9))
    + r"\s+heading gap after each corner \(deg\):"
    + "".join(rf"\s+(?P<corner{k}>{_NUMBER})" for k in range(1, 9))
)

CLAIMS["05_odometry"] = [
    Claim(
        says="The counts are large and differ between the wheels",
        printed=r"time \(s\)\s+wheel\s+ticks\s+[\d.]+\s+(?:left|right)\s+(?P<first>\d+)\s+"
        r"[\d.]+\s+(?:left|right)\s+(?P<second>\d+)",
        holds=lambda first, second: min(first, second) > 1000 and abs(first - second) > 1000,
        meaning="the first readings are counts in the thousands, far apart",
    ),
    Claim(
        says="the count goes **up** while the robot drives forward and **down** while it drives "
        "backwards",
        printed=_encoder_counts_05("left") + r"\s+" + _encoder_counts_05("right"),
        holds=lambda **n: (
            n["left_forward"] > 0 > n["left_backward"]
            and n["right_forward"] > 0 > n["right_backward"]
        ),
        meaning="each wheel's count rises while driving forward and falls while reversing",
    ),
    Claim(
        says="the two wheels do not count exactly alike (the realistic robot's right wheel is a "
        "little weaker)",
        printed=_encoder_counts_05("left") + r"\s+" + _encoder_counts_05("right"),
        holds=lambda **n: n["right_forward"] < n["left_forward"],
        meaning="the right wheel counts fewer ticks than the left while driving forward",
    ),
    Claim(
        says="after the backward drive is stopped, the counts still creep **up** a little",
        printed=_encoder_counts_05("left") + r"\s+" + _encoder_counts_05("right"),
        holds=lambda **n: 0 < n["left_end"] < 30 and 0 < n["right_end"] < 30,
        meaning="both counts rise by a few ticks after the reverse command is stopped",
    ),
    Claim(
        says="Each encoder publishes about every 33 ms (30 Hz)",
        printed=rf"left: \d+ readings in {_NUMBER} s, one every (?P<left>{_NUMBER}) ms.*\s+"
        rf"right: \d+ readings in {_NUMBER} s, one every (?P<right>{_NUMBER}) ms",
        holds=lambda left, right: 32 < left < 35 and 32 < right < 35,
        meaning="each wheel reports every 32 to 35 ms on average",
    ),
    Claim(
        says="on the realistic robot each reading comes a little early or late",
        printed=rf"one every (?P<mean>{_NUMBER}) ms \(from (?P<low>{_NUMBER}) to "
        rf"(?P<high>{_NUMBER}) ms\)",
        holds=lambda mean, low, high: mean - 15 < low < mean - 1 and mean + 1 < high < mean + 15,
        meaning="the time between two readings varies by a few milliseconds",
    ),
    Claim(
        says="Here the two clocks happen to tick almost together",
        printed=rf"the two wheels' first readings: (?P<apart>{_NUMBER}) ms apart",
        holds=lambda apart: apart < 5,
        meaning="the two wheels' first readings are less than 5 ms apart",
    ),
    Claim(
        says="now and then one wheel reports twice before the other reports once",
        printed=r"times a wheel reported twice in a row: (?P<twice>\d+)",
        holds=lambda twice: 0 < twice < 100,
        meaning="a wheel sometimes reports twice in a row",
    ),
    Claim(
        says="the robot should drive a circle of radius",
        printed=rf"diameter of the circle: (?P<diameter>{_NUMBER}) m",
        holds=lambda diameter: abs(diameter - 0.3) < 0.005,
        meaning="dead reckoning of constant wheel turns draws a circle of radius 0.15 m",
    ),
    Claim(
        says="It should end exactly where your node ended during the run",
        printed=rf"replayed offline: (?P<n1>\d+) poses, final pose \[(?P<x1>{_NUMBER})\s+"
        rf"(?P<y1>{_NUMBER})\s+(?P<t1>{_NUMBER})\]\s+the node, live: (?P<n2>\d+) poses, final "
        rf"pose \[(?P<x2>{_NUMBER})\s+(?P<y2>{_NUMBER})\s+(?P<t2>{_NUMBER})\]",
        holds=lambda n1, x1, y1, t1, n2, x2, y2, t2: (n1, x1, y1, t1) == (n2, x2, y2, t2),
        meaning="the replayed odometry ends where the live node ended",
    ),
    Claim(
        says="estimate against actual (about a centimetre for the ideal robot, tens of "
        "centimetres for the realistic one)",
        printed=_MISSION_GAPS_05,
        holds=lambda ideal, realistic, apart: 0.2 < ideal < 2 and 10 <= realistic < 100,
        meaning="odometry ends about 1 cm from the truth on the ideal robot, 10 to 100 cm on "
        "the realistic one",
    ),
    Claim(
        says="the realistic robot ended about 2 m from it",
        printed=_MISSION_GAPS_05,
        holds=lambda ideal, realistic, apart: 150 <= apart <= 260,
        meaning="the realistic robot ends 1.5 to 2.6 m from the ideal one",
    ),
    Claim(
        says="odometry catches this error, open-loop commands cannot",
        printed=_MISSION_GAPS_05,
        holds=lambda ideal, realistic, apart: realistic < apart / 4,
        meaning="the realistic odometry ends far closer to the truth than the truth to the plan",
    ),
    Claim(
        says="it follows the real robot far better than open-loop commands do",
        printed=_MISSION_GAPS_05,
        holds=lambda ideal, realistic, apart: realistic < apart / 4,
        meaning="the realistic odometry ends far closer to the truth than the truth to the plan",
    ),
    Claim(
        says="A tick in distance is tiny, but a tick of difference between the wheels is a "
        "heading error, and a heading error turns into a sideways error that grows with every "
        "metre.",
        printed=rf"one tick: {_NUMBER} deg of wheel, (?P<mm>{_NUMBER}) mm of mat.*\s+.*\s+a "
        rf"heading off by that much puts the robot (?P<cm>{_NUMBER}) cm aside",
        holds=lambda mm, cm: mm < 2 and 10 * cm > 5 * mm,
        meaning="a tick is under 2 mm of mat, but its heading error puts the robot over 5 times "
        "as far aside",
    ),
    Claim(
        says="do the tick counts show why?",
        printed=r"realistic, first straight leg: left (?P<left>\d+) ticks, right (?P<right>\d+)",
        holds=lambda left, right: right < left,
        meaning="the weaker right wheel counts fewer ticks on the realistic robot's first leg",
    ),
    Claim(
        says="does the gap grow with the time between the two readings of a pair?",
        printed="".join(_seed_row_05(seed) for seed in range(5)),
        holds=lambda **n: all(
            n[f"gap{a}"] < n[f"gap{b}"]
            for a in range(5)
            for b in range(5)
            if n[f"apart{a}"] + 1 < n[f"apart{b}"]
        ),
        meaning="the seeds whose readings are further apart end with larger gaps",
    ),
    Claim(
        says="the belief fades when the robot stops (to a tick or two of difference between the "
        "wheels, 0.85° each)",
        printed="".join(_seed_row_05(seed) for seed in range(5)),
        holds=lambda **n: (
            all(n[f"end{seed}"] <= 1.8 for seed in range(5)) and n["end4"] < n["most4"]
        ),
        meaning="the heading error at the end is at most two ticks' worth, and below the "
        "largest one",
    ),
    Claim(
        says="the ideal robot's odometry is off by several centimetres after the hard reversals, "
        "by about a centimetre after the slow and gentle runs",
        printed=_BACK_AND_FORTH_05,
        holds=lambda **n: (
            n["hard_ideal_off"] > 3 and max(n["slow_ideal_off"], n["gentle_ideal_off"]) < 2
        ),
        meaning="the ideal robot's gap is over 3 cm after the hard run, under 2 cm otherwise",
    ),
    Claim(
        says="only after the hard run does the realistic robot really end away from its start",
        printed=_BACK_AND_FORTH_05,
        holds=lambda **n: (
            n["hard_realistic_really"] >= 0.5
            and max(n["slow_realistic_really"], n["gentle_realistic_really"]) < 0.3
            and max(n[f"{run}_ideal_really"] for run in ("slow", "gentle", "hard")) < 0.3
        ),
        meaning="only the realistic robot's hard run ends away from the start",
    ),
    Claim(
        says="the realistic robot's odometry is off by more after the gentle run than after the "
        "slow one",
        printed=_BACK_AND_FORTH_05,
        holds=lambda **n: n["gentle_realistic_off"] > n["slow_realistic_off"] + 1,
        meaning="the realistic robot's gap grows with the speed (sign rule)",
    ),
    Claim(
        says="After the hard run the realistic robot's odometry is off by less than after the "
        "gentle one: its wrong ticks come at every reversal, in both directions, and partly "
        "cancel, and its slip moved it the same way its odometry errs.",
        printed=_BACK_AND_FORTH_05,
        holds=lambda **n: (
            n["hard_realistic_off"] < n["gentle_realistic_off"]
            and n["hard_realistic_says"] <= n["gentle_realistic_says"]
            and n["hard_realistic_off"] < n["hard_realistic_says"]
        ),
        meaning="hard run: a smaller gap, an odometry no further off the start, and the slip "
        "towards the odometry's end",
    ),
    Claim(
        says="so the position gap keeps growing (it shrinks only for a while, when the errors "
        "happen to point back)",
        printed=_LAPS_05,
        holds=lambda **n: (
            n["side8"] > 2 * n["side4"]
            and any(n[f"side{k + 1}"] < n[f"side{k}"] for k in range(1, 8))
        ),
        meaning="the realistic position gap after two laps is over twice that after one, and "
        "shrinks at times",
    ),
    Claim(
        says="A heading error made at one corner turns every later metre a little sideways",
        printed=_LAPS_05,
        holds=lambda **n: (
            abs(n["corner8"]) > 5
            and n["side8"] + n["side7"] + n["side6"] > 3 * (n["side1"] + n["side2"] + n["side3"])
        ),
        meaning="after a large heading gap the realistic position gap grows much faster",
    ),
    Claim(
        says="Where does the ideal robot's θ plot jump from 0 to 2π, and what is the robot "
        "doing then?",
        printed=rf"jumped from about 0 to about 2\*pi at t = (?P<jump>{_NUMBER}) s\s+a quarter "
        rf"turn to the right \(an arc\) is driven from t = (?P<start>{_NUMBER}) s to "
        rf"(?P<end>{_NUMBER}) s",
        holds=lambda jump, start, end: start < jump < end + 0.5,
        meaning="the ideal robot's heading wraps once, during or just after its first right turn",
    ),
    Claim(
        says="The ideal robot turned about the two quarter turns to the right you asked for.",
        printed=rf"ideal,\s+odometry: turned {_NUMBER} rad = (?P<odometry>{_NUMBER}) deg in "
        rf"total\s+ideal, ground truth: turned {_NUMBER} rad = (?P<truth>{_NUMBER}) deg",
        holds=lambda odometry, truth: -190 < odometry < -170 and -190 < truth < -170,
        meaning="the ideal robot turned 170 to 190 degrees clockwise in total",
    ),
    Claim(
        says="The realistic robot, given the same commands, turned far less",
        printed=rf"realistic, ground truth: turned {_NUMBER} rad = (?P<truth>{_NUMBER}) deg",
        holds=lambda truth: -120 < truth < 0,
        meaning="the realistic robot turned less than 120 degrees clockwise in total",
    ),
]

CLAIMS["06_driving"] = [
    Claim(
        says="about 30 times per second: each time a pair of encoder readings completes",
        printed=r"average rate: (?P<hz>[\d.]+)",
        holds=lambda hz: 28 <= hz <= 32,
        meaning="the odometry publishes about 30 poses a second",
    ),
    Claim(
        says="both lines go on a little after the zero command: forward after the first stop, "
        "backward after the last, the odometry in step with the truth",
        printed=r"after zero command 1: the odometry went on (?P<odometry1>[+-][\d.]+) cm, the "
        r"robot really (?P<truth1>[+-][\d.]+) cm[^\n]*\nafter zero command 2: the odometry went "
        r"on (?P<odometry2>[+-][\d.]+) cm, the robot really (?P<truth2>[+-][\d.]+) cm",
        holds=lambda odometry1, truth1, odometry2, truth2: (
            0 < odometry1 < 5
            and 0 < truth1 < 5
            and -5 < odometry2 < 0
            and -5 < truth2 < 0
            and abs(odometry1 - truth1) <= 0.3
            and abs(odometry2 - truth2) <= 0.3
        ),
        meaning="after each stop both go on a few cm, the move's way, within 3 mm of each other",
    ),
    Claim(
        says="so the first quarter turn ends right at θ = 0, where the heading wraps",
        printed=r"end of the first turn: odometry theta (?P<theta>[\d.]+) rad, theta - theta0 = "
        r"(?P<naive>[+-][\d.]+) rad, tracker total = (?P<tracker>[+-][\d.]+) rad",
        holds=lambda theta, naive, tracker: (
            theta > 3 * math.pi / 2 and abs(tracker + math.pi / 2) < 0.35
        ),
        meaning="the turn ends within 20° past θ = 0, so the odometry's θ wrapped to near 2π",
    ),
    Claim(
        says="What would a driver that stops when θ \u2212 θ₀ ≤ \u2212π/2 have done here?",
        printed=r"end of the first turn: odometry theta (?P<theta>[\d.]+) rad, theta - theta0 = "
        r"(?P<naive>[+-][\d.]+) rad, tracker total = (?P<tracker>[+-][\d.]+) rad",
        holds=lambda theta, naive, tracker: naive > 0 and tracker < -math.pi / 2,
        meaning="θ - θ₀ jumped at the wrap and ends positive, never below -π/2; the tracker did",
    ),
    Claim(
        says="a wheel of the realistic robot at rest needs PWM 83 (duty 0.12, the edge of its "
        "motors' dead band) to break free",
        printed=r"smallest speed that moved the realistic robot: (?P<smallest>[\d.]+) m/s \(PWM "
        r"(?P<pwm>\d+) needs u >= (?P<u>[\d.]+), v >= (?P<v>[\d.]+) m/s\)",
        holds=lambda smallest, pwm, u, v: (
            pwm == 83 and abs(u - 0.12) < 0.005 and v <= smallest <= v + 0.0026
        ),
        meaning="PWM 83 is duty 0.12, and the slowest speed that moved is the next one above it",
    ),
    Claim(
        says="It waits for the odometry to reach a goal that never comes",
        printed=r"v = 0\.03 m/s: (?P<done>\d+) of 2 moves done after (?P<seconds>\d+) s; the "
        r"robot moved (?P<moved>[\d.]+) cm",
        holds=lambda done, seconds, moved: done == 0 and moved < 0.1,
        meaning="at 0.03 m/s no move is done when the limit ends the run, the robot did not move",
    ),
    Claim(
        says="short of 1.25 m at every speed, and less so the faster it went",
        printed=r"the robot stopped (?P<slowest>[+-][\d.]+) to (?P<fastest>[+-][\d.]+) cm along "
        r"the heading \(the most: (?P<most>[+-][\d.]+) cm\)",
        holds=lambda slowest, fastest, most: most < 0 and fastest > slowest + 1,
        meaning="every speed stops before 1.25 m, the fastest over 1 cm closer than the slowest",
    ),
    Claim(
        says="when the odometry says 1.25 m, the robot has gone about 6 cm less",
        printed=r"the odometry was off by (?P<all_slowest>[\d.]+) to (?P<all_fastest>[\d.]+) cm: "
        r"(?P<along_slowest>[+-][\d.]+) to (?P<along_fastest>[+-][\d.]+) cm along the heading",
        holds=lambda all_slowest, all_fastest, along_slowest, along_fastest: (
            4.5 < along_slowest < 8 and 4.5 < along_fastest < 8
        ),
        meaning="along the heading the odometry is 4.5 to 8 cm ahead of the truth at every speed",
    ),
    Claim(
        says="The odometry's error grows with the speed too",
        printed=r"the odometry was off by (?P<all_slowest>[\d.]+) to (?P<all_fastest>[\d.]+) cm: "
        r"(?P<along_slowest>[+-][\d.]+) to (?P<along_fastest>[+-][\d.]+) cm along the heading, "
        r"(?P<side_slowest>[+-][\d.]+) to (?P<side_fastest>[+-][\d.]+) cm sideways",
        holds=lambda **n: (
            n["all_fastest"] > n["all_slowest"] + 1
            and abs(n["side_fastest"]) > abs(n["side_slowest"]) + 1
            and abs(n["along_fastest"] - n["along_slowest"]) < 1
        ),
        meaning="the odometry's error grows by its sideways part; its part along the heading stays",
    ),
    Claim(
        says="Does the true sideways drift depend on the speed?",
        printed=r"cm along the heading \(the most: [+-][\d.]+ cm\), (?P<side_slowest>[+-][\d.]+) "
        r"to (?P<side_fastest>[+-][\d.]+) cm to the side",
        holds=lambda side_slowest, side_fastest: abs(side_fastest - side_slowest) < 1,
        meaning="it hardly does: the true drift at the fastest and at the slowest speed are "
        "within 1 cm",
    ),
    Claim(
        says="the stop is only decided at the next odometry update and loop cycle",
        printed=r"ideal\s+straight \+1\.25 m\s+(?P<late>[+-][\d.]+) cm\s+"
        r"(?P<coasted>[+-][\d.]+) cm",
        holds=lambda late, coasted: 0 <= late <= 1.4 and coasted > 0,
        meaning="the stop is sent within two updates' travel past the goal (1.3 cm), then coasts",
    ),
    Claim(
        says="nobody corrects the drift that the realistic robot's unequal wheels cause",
        printed=r"realistic straight \+1\.25 m\s+[+-][\d.]+ cm\s+[+-][\d.]+ cm\s+[+-][\d.]+ cm\s+"
        r"[\d.]+ cm\s+(?P<side>[+-][\d.]+) cm",
        holds=lambda side: side < -1,
        meaning="the realistic robot ends the forward move over 1 cm to the right of its line",
    ),
    Claim(
        says='A negative "coasted" is worth a second look.',
        printed=r"realistic straight -1\.25 m\s+[+-][\d.]+ cm\s+(?P<coasted>[+-][\d.]+) cm",
        holds=lambda coasted: coasted < 0,
        meaning="the realistic robot's way back has a negative coasted (the sign rule)",
    ),
    Claim(
        says="how the wrong value scales each estimate",
        printed=r"R 5 % too large: the odometry says (?P<said>[\d.]+) m, the robot really went "
        r"(?P<went>[\d.]+) m\nbaseline 10 % too large: the odometry says (?P<said_turn>[+-][\d.]+)"
        r"°, the robot really turned (?P<turned>[+-][\d.]+)°",
        holds=lambda said, went, said_turn, turned: (
            1.03 < said / went < 1.07 and 1.06 < turned / said_turn < 1.14
        ),
        meaning="R 5 % too large scales the distance by about 5 %, the baseline the turn by 10 %",
    ),
    Claim(
        says="does either gap ever shrink for good?",
        printed=r"after lap 1: the robot (?P<plan1>[\d.]+) cm from the plan, your odometry "
        r"(?P<odometry1>[\d.]+) cm from the truth\nafter lap 2: the robot (?P<plan2>[\d.]+) cm "
        r"from the plan, your odometry (?P<odometry2>[\d.]+) cm from the truth",
        holds=lambda plan1, odometry1, plan2, odometry2: plan2 > plan1 and odometry2 > odometry1,
        meaning="neither: both gaps are larger after the second lap than after the first",
    ),
    Claim(
        says="after the zero command, the count goes **up** while the robot still rolls back",
        printed=r"hard stop: after the last zero command the robot rolled (?P<rolled>[+-][\d.]+) "
        r"cm, its right wheel's count went (?P<ticks>[+-]\d+) ticks",
        holds=lambda rolled, ticks: rolled < 0 and ticks > 0,
        meaning="after the hard stop the robot rolls back while the right wheel counts up",
    ),
    Claim(
        says="The odometry believes the robot went forward at the very end, and from then on "
        "every estimate carries that error",
        printed=r"hard stop:[^\n]*\n\s+the odometry saw the way back (?P<short>-?[\d.]+) cm "
        r"shorter, the first quarter turn (?P<turn>-?[\d.]+)° smaller",
        holds=lambda short, turn: short > 0.5,
        meaning="after a hard stop the odometry saw the way back over 5 mm shorter than it was",
    ),
    Claim(
        says="A clockwise turn on the spot ends the same way: its right wheel turns backwards",
        printed=r"hard stop:[^\n]*\n\s+the odometry saw the way back (?P<short>-?[\d.]+) cm "
        r"shorter, the first quarter turn (?P<turn>-?[\d.]+)° smaller",
        holds=lambda short, turn: turn > 1,
        meaning="after a hard stop the odometry saw the clockwise turn over 1° smaller than it was",
    ),
    Claim(
        says="Slowing down leaves less to coast, so fewer ticks go the wrong way, for a little "
        "more time",
        printed=r"hard stop: after the last zero command the robot rolled "
        r"(?P<hard_rolled>[+-][\d.]+) cm, its right wheel's count went "
        r"(?P<hard_ticks>[+-]\d+) ticks\n\s+the odometry saw "
        r"the way back (?P<hard_short>-?[\d.]+) cm shorter, the first quarter turn "
        r"(?P<hard_turn>-?[\d.]+)° smaller than they were\n\s+the two tasks took "
        r"(?P<hard_s>[\d.]+) s and (?P<hard_turn_s>[\d.]+) s\nslowed down: after the last zero "
        r"command the robot rolled (?P<slow_rolled>[+-][\d.]+) cm, its right wheel's count went "
        r"(?P<slow_ticks>[+-]\d+) ticks\n\s+the odometry saw the way back (?P<slow_short>-?[\d.]+)"
        r" cm shorter, the first quarter turn (?P<slow_turn>-?[\d.]+)° smaller than they were\n"
        r"\s+the two tasks took (?P<slow_s>[\d.]+) s and (?P<slow_turn_s>[\d.]+) s",
        holds=lambda **n: (
            abs(n["slow_rolled"]) < abs(n["hard_rolled"])
            and n["slow_ticks"] < n["hard_ticks"]
            and n["slow_short"] < n["hard_short"]
            and n["slow_turn"] < n["hard_turn"]
            and n["slow_s"] > n["hard_s"]
            and n["slow_turn_s"] >= n["hard_turn_s"]
        ),
        meaning="slowed down, the robot rolls less after the stop, fewer ticks count up, the "
        "odometry's errors are smaller and the tasks take longer",
    ),
    Claim(
        says="Launched nodes start when the robot next runs, so the first list has only the "
        "robot's own nodes",
        printed=r"launched, before the robot runs:\n(?:(?!/\w+/(?:driver|odometry|recorder)_node\n)"
        r"/\S+\n)+\nwhile driving:",
        holds=lambda: True,
        meaning="the list before the robot runs has no driver, odometry or recorder node",
    ),
    Claim(
        says="the driver has a list of moves, so it loops, and when the list is done it returns",
        printed=r"\ndone:\n(?:(?!/\w+/driver_node\n)/\S+\n)*/\w+/odometry_node\n"
        r"(?:(?!/\w+/driver_node\n)/\S+\n)*\n",
        holds=lambda: True,
        meaning="once the moves are done, the driver has left the node list and the odometry stays",
    ),
    Claim(
        says="`forgetful_driver` drives until the odometry says 0.3 m, then simply returns: no "
        "zero command, no shutdown hook",
        printed=r"driver_node\s+returned at\s+[\d.]+ s\s+False\s+(?P<returned>[\d.]+) cm\n"
        r"driver_node\s+killed\s+at\s+[\d.]+ s\s+False\s+(?P<killed>[\d.]+) cm\n"
        r"forgetful_driver\s+returned at\s+[\d.]+ s\s+False\s+(?P<forgetful_returned>[\d.]+) cm\n"
        r"forgetful_driver\s+killed\s+at\s+[\d.]+ s\s+False\s+(?P<forgetful_killed>[\d.]+) cm",
        holds=lambda **n: (
            n["returned"] < 3
            and n["killed"] < 3
            and n["forgetful_returned"] > 30
            and n["forgetful_killed"] > 30
        ),
        meaning="the forgetful driver leaves the robot driving however it ends, driver_node not",
    ),
    Claim(
        says="the node lists above (which nodes remain after the driver is done, and why), the "
        "last command recorded",
        printed=r"last command, at t = [\d.]+ s: v = (?P<v>-?[\d.]+) m/s, omega = "
        r"(?P<omega>-?[\d.]+) rad/s\nwheel speeds now: left (?P<left>-?[\d.]+) rad/s, right "
        r"(?P<right>-?[\d.]+) rad/s",
        holds=lambda v, omega, left, right: v == omega == left == right == 0,
        meaning="the driver's last command was a zero command, and the wheels stand still",
    ),
    Claim(
        says="motor lag, more at higher speed",
        printed=r"the robot stopped (?P<slowest>[+-][\d.]+) to (?P<fastest>[+-][\d.]+) cm along "
        r"the heading",
        holds=lambda slowest, fastest: fastest > slowest + 1,
        meaning="the robot goes further after the stop at the fastest speed than at the slowest",
    ),
    Claim(
        says="Too slow and the wheels never start: the driver would wait forever.",
        printed=r"v = 0\.03 m/s: (?P<done>\d+) of 2 moves done after (?P<seconds>\d+) s; the "
        r"robot moved (?P<moved>[\d.]+) cm",
        holds=lambda done, seconds, moved: done == 0 and moved < 0.1,
        meaning="at 0.03 m/s the robot never moved and no move was done",
    ),
]

_CONTROL_PID_ROW = r"\n\s+{error}\s+(?P<p>[\d.]+)\s+(?P<pi>[\d.]+)\s+(?P<pd>[\d.]+)"
_CONTROL_LAST_ROWS = (
    r"\n\s+0\.03\s+(?P<p1>[\d.]+)\s+(?P<pi1>[\d.]+)\s+(?P<pd1>[\d.]+)\s*"
    r"\n\s+0\.03\s+(?P<p2>[\d.]+)\s+(?P<pi2>[\d.]+)\s+(?P<pd2>[\d.]+)\s*"
    r"\n\s+0\.03\s+(?P<p3>[\d.]+)\s+(?P<pi3>[\d.]+)\s+(?P<pd3>[\d.]+)"
)
_CONTROL_OPEN_LOOP = (
    r"straight, really:\s+(?P<gap>[\d.]+) cm from the goal,\s+(?P<right>-?[\d.]+) cm right of the "
    r"line, heading\s+(?P<truth>[\d.]+) deg\nstraight, odometry:[^\n]*heading\s+"
    r"(?P<odometry>[\d.]+) deg\nturn,\s+really:[^\n]*heading - target =\s+"
    r"(?P<turn_truth>[+-][\d.]+) deg\nturn,\s+odometry:[^\n]*heading - target =\s+"
    r"(?P<turn_odometry>[+-][\d.]+) deg"
)
_CONTROL_STEPS = (
    r"P, kp = 2:\s+never\s+(?P<p2_past>[\d.]+) deg\s+(?P<p2_odometry>-?[\d.]+) deg\s+"
    r"(?P<p2_really>-?[\d.]+) deg\n\s*P, kp = 16:\s+(?P<p16_settle>[\d.]+) s\s+(?P<p16_past>[\d.]+)"
    r" deg\s+(?P<p16_odometry>-?[\d.]+) deg\s+(?P<p16_really>-?[\d.]+) deg\n\s*PI, kp = 3, ki = "
    r"0\.6:\s+never\s+(?P<pi_past>[\d.]+) deg\s+(?P<pi_odometry>-?[\d.]+) deg\s+"
    r"(?P<pi_really>-?[\d.]+) deg\n\s*PID, kp = 16, ki = 0\.6, kd = 0\.6:\s+(?P<pid_settle>[\d.]+) "
    r"s\s+(?P<pid_past>[\d.]+) deg\s+(?P<pid_odometry>-?[\d.]+) deg\s+(?P<pid_really>-?[\d.]+) deg"
)
_CONTROL_SWEEP_ROW = (
    r"PI, kp = {kp}, ki = 0\.6:\s+(?P<settle>[\d.]+) s\s+(?P<past>[\d.]+) deg\s+"
    r"(?P<odometry>-?[\d.]+) deg\s+(?P<really>-?[\d.]+) deg"
)
_CONTROL_CORNERS = (
    r"  really:\s+(?P<really>[\d.]+) cm from the last corner\nodometry:\s+(?P<odometry>[\d.]+) cm "
    r"from the last corner\nwhen the odometry reached each corner, the robot really was "
    r"(?P<first>[\d.]+) cm, [\d.]+ cm, [\d.]+ cm away"
)
_CONTROL_OPEN_CLOSED = (
    r"straight: really from the goal \(cm\)\s+(?P<open_really>[\d.]+)\s+(?P<closed_really>[\d.]+)"
    r"\n\s*straight: odometry from the goal \(cm\)\s+(?P<open_odometry>[\d.]+)\s+"
    r"(?P<closed_odometry>[\d.]+)\n\s*turn: really from the target \(deg\)\s+(?P<open_turn>[\d.]+)"
    r"\s+(?P<closed_turn>[\d.]+)"
)
CLAIMS["07_control"] = [
    Claim(
        says="from θ = 350° to a target of 10° is a turn of **+20°**, not \u2212340°",
        printed=r"raw difference target - theta:\s+(?P<raw>[+-][\d.]+) deg\n"
        r"angle_error\(target, theta\):\s+(?P<wrapped>[+-][\d.]+) deg",
        holds=lambda raw, wrapped: raw == -340 and wrapped == 20,
        meaning="the raw difference is -340°, angle_error +20°",
    ),
    Claim(
        says="at first the commands are clipped at the limit of 2 rad/s",
        printed=_CONTROL_PID_ROW.format(error=r"1\.20"),
        holds=lambda p, pi, pd: p == pi == pd == 2.0,
        meaning="for the first error, P, PI and PD all send 2 rad/s",
    ),
    Claim(
        says="While the error drops fast, the PD command is lower than P's: the D term brakes.",
        printed=_CONTROL_PID_ROW.format(error=r"0\.50"),
        holds=lambda p, pi, pd: pd < p < pi,
        meaning="while the error drops, PD's command is below P's (and PI's above)",
    ),
    Claim(
        says="When the error stops changing, the D term is 0 and PD equals P; P's 0.06 rad/s "
        "cannot move a wheel at rest",
        printed=_CONTROL_LAST_ROWS,
        holds=lambda p2, pd2, p3, pd3, **_: p2 == pd2 == p3 == pd3 == 0.06,
        meaning="with the error steady at 0.03 rad, P and PD both send 0.06 rad/s",
    ),
    Claim(
        says="PI's command is a little larger all along and keeps growing, slowly, while the "
        "error stays",
        printed=_CONTROL_LAST_ROWS,
        holds=lambda p1, pi1, pi2, pi3, **_: p1 < pi1 < pi2 < pi3 < pi1 + 0.01,
        meaning="with the error steady, PI's command is above P's and grows by under 0.01 rad/s",
    ),
    Claim(
        says="the robot curved to the right (the weaker right wheel): it ended facing a few "
        "degrees right of 90° and a few centimetres to the right of the line",
        printed=_CONTROL_OPEN_LOOP,
        holds=lambda right, truth, **_: 80 < truth < 89 and 2 < right < 10,
        meaning="the open-loop robot ends facing 1 to 10° right of 90°, 2 to 10 cm right",
    ),
    Claim(
        says="the **odometry saw the turn**: its heading at the end is as far from 90°",
        printed=_CONTROL_OPEN_LOOP,
        holds=lambda truth, odometry, **_: odometry < 89 and abs(truth - odometry) < 1,
        meaning="the odometry's final heading is within 1° of the true one",
    ),
    Claim(
        says="the quarter turn went past the target, by the odometry and even more really",
        printed=_CONTROL_OPEN_LOOP,
        holds=lambda turn_truth, turn_odometry, **_: turn_truth < turn_odometry < 0,
        meaning="the open-loop turn ends past the target, really further than by the odometry",
    ),
    Claim(
        says="Both end facing about 10°, but the raw difference sends the robot the long way "
        "round, almost a whole turn clockwise at the top turn rate",
        printed=r"angle_error \(wrapped\): turned\s+(?P<short>[+-][\d.]+) deg, ended at\s+"
        r"(?P<short_end>[\d.]+) deg\n\s*raw difference target - theta: turned\s+"
        r"(?P<long>[+-][\d.]+) deg, ended at\s+(?P<long_end>[\d.]+) deg",
        holds=lambda short, short_end, long, long_end: (
            abs(short_end - 10) < 3 and abs(long_end - 10) < 3 and 0 < short < 40 and long < -300
        ),
        meaning="both runs end within 3° of 10°; the raw one turned over 300° clockwise",
    ),
    Claim(
        says="**P, kp = 2** slows down gently but stops far short",
        printed=_CONTROL_STEPS,
        holds=lambda p2_past, p2_odometry, p2_really, **_: (
            p2_past == 0 and p2_odometry > 10 and 0.7 < 2 * math.radians(p2_odometry) < 1.3
        ),
        meaning="P, kp = 2 never goes past and stops over 10° short, where kp·e is about 1 rad/s",
    ),
    Claim(
        says="**P, kp = 16** gets there fast, but it reaches the target still turning at full "
        "rate; the motors lag, so it goes past, reverses, and settles wherever the dead zone "
        "stops it",
        printed=_CONTROL_STEPS,
        holds=lambda **n: (
            n["p16_settle"] < 2
            and n["p16_past"] > 2
            and n["p16_odometry"] < 0
            and n["p16_really"] < 0
        ),
        meaning="P, kp = 16 is within 2° in under 2 s, goes over 2° past and stays past",
    ),
    Claim(
        says="with a small kp and ki = 0.6 it has a long way to build up from, longer than this "
        "run",
        printed=_CONTROL_STEPS,
        holds=lambda pi_past, pi_odometry, **_: pi_odometry > 2,
        meaning="the PI controller never gets within 2° in the run",
    ),
    Claim(
        says="**PID**: the D term brakes the fast P controller before the target: it settles "
        "first and goes past by far less, ending within 2° of the target by the odometry and "
        "really",
        printed=_CONTROL_STEPS,
        holds=lambda **n: (
            n["pid_settle"] < n["p16_settle"]
            and n["pid_past"] < n["p16_past"] / 3
            and abs(n["pid_odometry"]) < 2
            and abs(n["pid_really"]) < 2
        ),
        meaning="the PID settles before P, kp = 16 (the others never do), goes past by under a "
        "third as much, within 2° by the odometry and really",
    ),
    Claim(
        says="the controllers that went past the target and came back end with the odometry and "
        "the truth apart, the more so the further they went past (P, kp = 16: several degrees); "
        "the two that never went past end where their odometry says, within a degree",
        printed=_CONTROL_STEPS,
        holds=lambda **n: (
            abs(n["p16_odometry"] - n["p16_really"]) > 3
            and n["pid_past"] < n["p16_past"]
            and abs(n["pid_odometry"] - n["pid_really"]) < abs(n["p16_odometry"] - n["p16_really"])
            and n["p2_past"] == n["pi_past"] == 0
            and abs(n["p2_odometry"] - n["p2_really"]) < 1
            and abs(n["pi_odometry"] - n["pi_really"]) < 1
        ),
        meaning="P, kp = 16 ends with odometry and truth over 3° apart, the PID (past by less) "
        "closer; P, kp = 2 and PI never go past and end within 1°",
    ),
    Claim(
        says="At a small kp the turn is slow: what does the integral do during all that time?",
        printed=_CONTROL_SWEEP_ROW.format(kp=r"1\.0"),
        holds=lambda settle, past, odometry, really: settle > 2,
        meaning="at kp = 1 the integral brings the robot within 2°, after over 2 s",
    ),
    Claim(
        says="At a large kp, is the odometry still right about where the robot ended?",
        printed=_CONTROL_SWEEP_ROW.format(kp=r"16\.0"),
        holds=lambda past, odometry, really, **_: past > 2 and abs(odometry - really) > 2,
        meaning="at kp = 16 the robot goes past and the odometry ends over 2° from the truth",
    ),
    Claim(
        says="Pick the gains where the robot settles quickly **and** the odometry and the truth "
        "agree",
        printed=_CONTROL_SWEEP_ROW.format(kp=r"8\.0"),
        holds=lambda settle, odometry, really, **_: settle < 1.5 and abs(odometry - really) < 1,
        meaning="kp = 8 (the gains used in section 5) settles in under 1.5 s, odometry and truth "
        "within 1°",
    ),
    Claim(
        says="by the odometry the robot went through every corner and ended about 2 cm from the "
        "last one, but really it ended more than a metre away, and it was already far from the "
        "first corner when the odometry reached it",
        printed=_CONTROL_CORNERS,
        holds=lambda really, odometry, first: odometry < 4 and really > 100 and first > 10,
        meaning="odometry within 4 cm of the last corner, the truth over 1 m away, and over "
        "10 cm from the first corner when the odometry reached it",
    ),
    Claim(
        says="The last run is the same drive with encoders that count the way the wheels really "
        "turn: it ends within a few centimetres of the corner",
        printed=r"encoders counting the way the wheels turn: really (?P<really>[\d.]+) cm, by the "
        r"odometry (?P<odometry>[\d.]+) cm",
        holds=lambda really, odometry: really < 5,
        meaning="without the sign rule the robot really ends within 5 cm of the last corner",
    ),
    Claim(
        says='which of the two, "really" or "odometry", does the controller bring to the '
        "goal, and how close?",
        printed=_CONTROL_OPEN_CLOSED,
        holds=lambda closed_really, open_odometry, closed_odometry, **_: (
            closed_odometry < min(closed_really, open_odometry)
        ),
        meaning="closed loop, the odometry ends closer to the goal than the robot really does",
    ),
    Claim(
        says="Can a controller correct an error that its measurement does not see?",
        printed=r"straight: really from the goal \(cm\)\s+[\d.]+\s+(?P<really>[\d.]+)[\s\S]*"
        r"closed loop, straight: the odometry ends (?P<gap>[\d.]+) cm from where the robot "
        r"really is",
        holds=lambda really, gap: gap > 2 and really - gap < 2,
        meaning="closed loop, most of what is left is the odometry's own error",
    ),
    Claim(
        says="It removes the errors the measurement can see: unequal wheels, the dead zone, "
        "coasting.",
        printed=_CONTROL_OPEN_CLOSED,
        holds=lambda **n: (
            n["open_turn"] > 5
            and n["closed_turn"] < 1
            and n["closed_odometry"] < n["open_odometry"]
        ),
        meaning="closed loop, the turn ends within 1° (open loop over 5°) and the straight closer "
        "to its goal by the odometry, the measurement",
    ),
    Claim(
        says="Gentle gains that settle without overshoot keep the odometry honest",
        printed=_CONTROL_STEPS,
        holds=lambda **n: (
            abs(n["p16_odometry"] - n["p16_really"]) > 3
            and n["pid_past"] < n["p16_past"] / 3
            and abs(n["pid_odometry"] - n["pid_really"]) < 2
        ),
        meaning="the overshooting P ends with odometry and truth over 3° apart, the PID (past by "
        "under a third as much) within 2°",
    ),
    Claim(
        says="The controller can only be as good as its measurement.",
        printed=_CONTROL_CORNERS,
        holds=lambda really, odometry, first: odometry < 3 and really > 20,
        meaning="through the corners the odometry ends within 3 cm, the robot over 20 cm away",
    ),
]


CLAIMS["08_leds"] = [
    Claim(
        says="Nothing follows `---`: the **response is empty**.",
        printed=r"std_msgs/String pattern_name\n  string data\n---\n(?s:.*?)an empty "
        r"response:\s+''",
        holds=lambda: True,
        meaning="ChangePattern's request is one std_msgs/String and its response has no field",
    ),
    Claim(
        says="The call returns once the emitter has handled the request, so the LEDs have changed "
        "by the next line.",
        printed=r"before the call, the LEDs show: WHITE\n[^\n]*\nafter the call, the LEDs "
        r"show:\s+RED",
        holds=lambda: True,
        meaning="the LEDs show RED on the line right after the call",
    ),
    Claim(
        says="The RGB values are 0.8, not 1: the emitter dims every named colour to 80 %.",
        printed=rf'color_list: \["red"(?:, "red"){{4}}\]\s+rgb_vals:\s+-\s+r: (?P<red>{_NUMBER})',
        holds=lambda red: abs(red - 0.8) < 1e-6,
        meaning="the emitter's RED is 0.8 in the red channel",
    ),
    Claim(
        says="The first message came before any call: the latched message of the RED you set above",
        printed=rf"\[INFO\] \[(?P<call>{_NUMBER})\] \[/duckiebot/led_emitter_node\]: Pattern "
        rf"changed to GREEN\.(?s:.*?)\nt = (?P<first>{_NUMBER}) s: \['red'",
        holds=lambda call, first: first < call,
        meaning="the listener's first message, RED, came before the first call",
    ),
    Claim(
        says="In CAR_SIGNAL_A the white LEDs (0, 2 and 4) blink at 4 Hz: on for 1/8 s, off for "
        "1/8 s.",
        printed=rf"CAR_SIGNAL_A: LEDs \[0, 2, 4\] \(white\) blink at (?P<hz>{_NUMBER}) Hz, on for "
        rf"(?P<on>{_NUMBER}) s, off for as long",
        holds=lambda hz, on: hz == 4 and on == 0.125,
        meaning="CAR_SIGNAL_A blinks its white LEDs 0, 2 and 4 at 4 Hz, 0.125 s on",
    ),
    Claim(
        says="Names are case-sensitive (with one exception, kept from Duckietown's table).",
        printed=r"Pattern 'red' ignored(?s:.*?)Pattern changed to light_off\.",
        holds=lambda: True,
        meaning="the emitter ignores 'red' but knows 'light_off'",
    ),
    Claim(
        says="An unknown name is only logged, and ignored.",
        printed=r"\[ERROR\][^\n]*Pattern 'PURPLE' ignored[^\n]*\n  the call returned normally; "
        r"the LEDs show CAR_SIGNAL_A",
        holds=lambda: True,
        meaning="asking the emitter for PURPLE logs an error, returns normally, changes nothing",
    ),
    Claim(
        says="Your node offers `set_color` and subscribes to the robot's `shutdown` topic.",
        printed=r"Node \[/duckiebot/light_service_node\]\nPublications:\n None\n\nSubscriptions:\n"
        r" \* /duckiebot/shutdown \[std_msgs/Empty\]\n\nServices:\n \* "
        r"/duckiebot/light_service_node/set_color",
        holds=lambda: True,
        meaning="rosnode info lists the shutdown subscription and the set_color service only",
    ),
    Claim(
        says="A refused colour leaves the LEDs as they were, nothing is logged as an error",
        printed=r"asking set_color for 'PURPLE'\n(?:(?!\[ERROR\])[^\n]*\n)*?  the LEDs show GREEN\n"
        r"\nasking set_color for 'red'\n(?:(?!\[ERROR\])[^\n]*\n)*?  the LEDs show GREEN\n",
        holds=lambda: True,
        meaning="after PURPLE and 'red' are refused the LEDs still show GREEN, with no error line",
    ),
    Claim(
        says="the caller learns at once what went wrong and what would be right",
        printed=r"refused: [^\n]*'PURPLE'[^\n]*WHITE, RED, GREEN, BLUE, YELLOW, LIGHT_OFF",
        holds=lambda: True,
        meaning="the refusal names the colour asked for and the valid ones",
    ),
    Claim(
        says="The LEDs start WHITE (the emitter's first pattern), change exactly when each call "
        "was made",
        printed=rf"on led_pattern:\n  t = (?P<t0>{_NUMBER}) s: LED 0 is white\n  t = "
        rf"(?P<t1>{_NUMBER}) s: LED 0 is red\n  t = (?P<t2>{_NUMBER}) s: LED 0 is green\n  "
        rf"t = (?P<t3>{_NUMBER}) s: LED 0 is blue\n  t = (?P<t4>{_NUMBER}) s: LED 0 is yellow\n",
        holds=lambda t0, t1, t2, t3, t4: (t0, t1, t2, t3, t4) == (0, 1, 2, 3, 4),
        meaning="WHITE at 0 s, then one colour at each call, 1 s apart",
    ),
    Claim(
        says="keep the last colour after the light service has stopped, at t = 5 s",
        printed=rf"the light service stopped at t = (?P<stopped>{_NUMBER}) s\nat t = "
        rf"(?P<later>{_NUMBER}) s the LEDs show YELLOW",
        holds=lambda stopped, later: abs(stopped - 5) < 0.06 and later > stopped,
        meaning="the light service stops at 5 s and the LEDs still show YELLOW after it",
    ),
]

_REALISTIC_09 = (
    rf"realistic: odometry (?P<gap>{_NUMBER}) cm and {_NUMBER} deg from the truth; really "
    rf"(?P<home>{_NUMBER}) cm from the start; [^\n]*believed it was (?P<believed>{_NUMBER}) "
    rf"cm[^\n]*\n\s+after the square: heading (?P<odometry>{_NUMBER}) deg by odometry, "
    rf"(?P<truth>{_NUMBER}) deg really\n\s+the circle: (?P<across>{_NUMBER}) m across by "
    rf"odometry \(asked: (?P<asked>{_NUMBER}) m\); travelled (?P<wheels>{_NUMBER}) m by "
    rf"odometry, (?P<moved>{_NUMBER}) m really\n\s+nearest the mat's edge: (?P<edge>{_NUMBER}) cm "
    r"(?P<side>inside|beyond) it[^\n]*during (?P<state>\w+)"
)
_TURNS_09 = (
    rf"ideal: \d+ turns, (?P<ideal_turns>{_NUMBER}) s of the (?P<ideal_total>{_NUMBER}) s "
    rf"mission, the longest {_NUMBER} s; {_NUMBER} s of it asking for less than {_NUMBER} "
    rf"rad/s\n\s*realistic: \d+ turns, (?P<turns>{_NUMBER}) s of the (?P<total>{_NUMBER}) s "
    rf"mission, the longest (?P<longest>{_NUMBER}) s; (?P<weak>{_NUMBER}) s of it asking for "
    rf"less than (?P<edge>{_NUMBER}) rad/s"
)
_SPIN_09 = (
    rf"0\.80\s+(?P<ideal>{_NUMBER}) deg\s+(?P<at80>{_NUMBER}) deg\n\s+0\.90\s+{_NUMBER} deg\s+"
    rf"(?P<at90>{_NUMBER}) deg\n\s+1\.00\s+{_NUMBER} deg\s+(?P<at100>{_NUMBER}) deg\n(?s:.*?)"
    rf"the slowest that turned the realistic robot: (?P<edge>{_NUMBER}) rad/s"
)
_QUARTER_TURN_09 = (
    rf"without a minimum:\s+(?P<slow>{_NUMBER}) s, ended (?P<slow_error>{_NUMBER}) deg[^\n]*\n"
    rf"\s+never below {_NUMBER} rad/s:\s+(?P<fast>{_NUMBER}) s, ended (?P<fast_error>{_NUMBER}) "
    "deg"
)

CLAIMS["09_mission"] = [
    Claim(
        says="let 7 s pass: the first wait is over and the square has just begun",
        printed=rf"at t = (?P<t>{_NUMBER}) s the LEDs show GREEN",
        holds=lambda t: 5 < t < 10,
        meaning="at 7 s the LEDs show the square's GREEN",
    ),
    Claim(
        says="*What to look for:* `mission_node` and `light_service_node` are gone.",
        printed=r"the nodes still running:\n(?:/duckiebot/(?!mission_node\n|light_service_node\n)"
        r"\S+\n)*(?!/)",
        holds=lambda: True,
        meaning="neither the mission node nor the light service is in the list of nodes running",
    ),
    Claim(
        says="The robot's drivers and the odometry node keep running",
        printed=r"the nodes still running:\n(?:/\S+\n)*/duckiebot/odometry_node\n",
        holds=lambda: True,
        meaning="the odometry node is still running after the mission",
    ),
    Claim(
        says="On the ideal robot both are small",
        printed=rf"odometry vs truth: (?P<apart>{_NUMBER}) cm and {_NUMBER} deg apart\nthe robot "
        rf"really ended (?P<home>{_NUMBER}) cm from its start",
        holds=lambda apart, home: apart < 2 and home < 2,
        meaning="on the ideal robot odometry and truth, and truth and start, are within 2 cm",
    ),
    Claim(
        says='the "D" drives up the straight back of the letter, then around its bowl with two '
        "clockwise quarter arcs",
        printed=r"d\s+GREEN\s+straight 1\.25 m, rotate -90°, [^\n]*arc r=0\.4 m, -90°[^\n]*arc "
        r"r=0\.4 m, -90°",
        holds=lambda: True,
        meaning="the D mission's state d has a straight back and two clockwise quarter arcs",
    ),
    Claim(
        says="after the square its heading is already off by more than 10°",
        printed=_REALISTIC_09,
        holds=lambda **n: n["odometry"] - n["truth"] > 10,
        meaning="after the square the realistic robot's true heading is over 10 degrees short",
    ),
    Claim(
        says="by odometry its circle is wider than asked",
        printed=_REALISTIC_09,
        holds=lambda **n: n["across"] > 1.1 * n["asked"],
        meaning="the realistic robot's circle is over 10 % wider than asked by odometry",
    ),
    Claim(
        says="real robot even leaves the mat and drives its circle partly off it",
        printed=_REALISTIC_09,
        holds=lambda **n: n["side"] == "beyond" and n["edge"] > 10 and n["state"] == "circle",
        meaning="the realistic robot is over 10 cm beyond the mat's edge, furthest during the "
        "circle",
    ),
    Claim(
        says="It ends far from the start while its odometry believes it is within a few "
        "centimetres of home.",
        printed=_REALISTIC_09,
        holds=lambda **n: n["home"] > 10 and n["believed"] < 8,
        meaning="the realistic robot ends over 10 cm from the start, its odometry within 8 cm",
    ),
    Claim(
        says="`MIN_TURN_RATE` is a little above it",
        printed=_SPIN_09,
        holds=lambda **n: n["edge"] < 1.2 <= n["edge"] + 0.3,
        meaning="MIN_TURN_RATE (1.2 rad/s) is above the slowest turn that moved the realistic "
        "robot, by 0.3 rad/s at most",
    ),
    Claim(
        says="the realistic robot does not turn at all below about 1 rad/s",
        printed=_SPIN_09,
        holds=lambda **n: n["at80"] == n["at90"] == n["at100"] == 0 and 0.9 < n["edge"] < 1.2,
        meaning="the realistic robot turns nothing at 0.8 to 1.0 rad/s, and starts below 1.2",
    ),
    Claim(
        says="(the ideal robot turns at every one of these commands)",
        printed=_SPIN_09,
        holds=lambda **n: n["ideal"] > 1,
        meaning="the ideal robot turns at the smallest command of the table",
    ),
    Claim(
        says="your turns on the spot took about as long on the realistic robot as on the ideal "
        "one, and only their last degrees, within three tolerances of the goal, asked for less",
        printed=_TURNS_09,
        holds=lambda **n: (
            n["turns"] < 1.3 * n["ideal_turns"] and n["weak"] < n["turns"] / 3 and n["longest"] < 5
        ),
        meaning="the realistic run spends under 1.3 times the ideal run's time turning on the "
        "spot, no turn lasts 5 s, and under a third of it asks for less than the dead band's edge",
    ),
    Claim(
        says="it takes a second or two instead of many, and ends within the tolerance all the same",
        printed=_QUARTER_TURN_09,
        holds=lambda slow, slow_error, fast, fast_error: (
            fast < 2.5 and slow > 3 * fast and slow_error < 2 and fast_error < 2
        ),
        meaning="with a minimum command the quarter turn takes under 2.5 s, a third of the time "
        "or less, both within 2 degrees",
    ),
]

_GAPS_11 = (
    rf"left_wheel_encoder_node/tick: \d+ ticks, intervals (?P<left_low>{_NUMBER}) to "
    rf"(?P<left_high>{_NUMBER}) ms, (?P<left_gaps>\d+) gap\(s\)\n[^\n]*right_wheel_encoder_node/"
    rf"tick: \d+ ticks, intervals (?P<right_low>{_NUMBER}) to (?P<right_high>{_NUMBER}) ms, "
    r"(?P<right_gaps>\d+) gap\(s\)"
)
_DROPPED_11 = (
    rf"(?P<dropped>\d+) messages taken out; stamp_gaps finds \(s\):\n  from (?P<start>{_NUMBER}) "
    rf"to (?P<end>{_NUMBER}): (?P<silent>{_NUMBER}) ms of silence\n(?!  from)"
)

CLAIMS["11_to_the_robot"] = [
    Claim(
        says="simulated, far faster than real time: minutes of mission in seconds",
        printed=rf"total time (?P<simulated>{_NUMBER}) s \(simulated\), run in "
        rf"(?P<wall>{_NUMBER}) s",
        holds=lambda simulated, wall: simulated > 60 and wall < simulated / 10,
        meaning="a mission of over a minute runs at least 10 times faster than real time",
    ),
    Claim(
        says="The walrus `:=` came in Python 3.8 itself: it parses, and the robot runs it.",
        printed=r"walrus :=, new in Python 3\.(?P<minor>\d+) +parses as Python 3\.8",
        holds=lambda minor: minor == 8,
        meaning="the walrus, new in 3.8, parses as Python 3.8",
    ),
    Claim(
        says="`match` and `except*` are syntax that Python 3.8 does not have: the check rejects "
        "them",
        printed=r"match, new in Python 3\.(?P<match>\d+) +rejected: [^\n]*\nexcept\*, new in "
        r"Python 3\.(?P<star>\d+) +rejected: ",
        holds=lambda match, star: match > 8 and star > 8,
        meaning="match and except*, newer than 3.8, are rejected",
    ),
    Claim(
        says="The last two parse, yet fail on the robot when they run",
        printed=r"list\[float\] hint, new in Python 3\.(?P<hint>\d+) +parses as Python 3\.8\n"
        r"str\.removesuffix, new in Python 3\.(?P<method>\d+) +parses as Python 3\.8",
        holds=lambda hint, method: hint > 8 and method > 8,
        meaning="the list[float] hint and str.removesuffix, newer than 3.8, parse as 3.8",
    ),
    Claim(
        says='`required="true"` on the mission node',
        printed=r'<node name="mission_node"[^>]*required="true"',
        holds=lambda: True,
        meaning="course.launch marks the mission node required",
    ),
    Claim(
        says="What stays on the laptop: every duckielib module that is **not** in that list (the "
        "simulator, the bags, the plots, the runner)",
        printed=r"laptop only: (?P<modules>\d+) modules, in duckielib/bags, (?:duckielib/\w+, )*"
        r"duckielib/plots, duckielib/sim, duckielib/tools\n",
        holds=lambda modules: modules > 0,
        meaning="the simulator, bags, plots and tools (the runner) stay on the laptop",
    ),
    Claim(
        says="Here: the standard library (`math`, `os`), numpy, rospy, the message packages and "
        "`duckielib.missions` (in the list above): all of them on the robot.",
        printed=r"duckielib/missions\.py(?s:.*?)solution\.py imports:\n(?:  (?:import "
        r"(?:math|os|rospy|numpy as np)|from (?:duckielib\.missions|duckietown_msgs\.msg|"
        r"duckietown_msgs\.srv|std_msgs\.msg) import [^\n]+)\n)+(?!  )",
        holds=lambda: True,
        meaning="solution.py imports only math, os, numpy, rospy, message packages and "
        "duckielib.missions, which is deployed",
    ),
    Claim(
        says="Zero commands on shutdown, zero commands on an exception, a shutdown when a "
        "callback fails, and the wheels driver's emergency stop when the encoders fall silent.",
        printed=r"shutdown hook publishes zero commands(?s:.*?)stops the wheels, then lets"
        r"(?s:.*?)the guard shuts the node down(?s:.*?)encoder silence:(?s:.*?)engages the "
        r"wheels driver's emergency stop",
        holds=lambda: True,
        meaning="the guard's description lists the four cases",
    ),
    Claim(
        says="the ticks stop, the robot does not",
        printed=rf"without:\s+(?P<rolled>{_NUMBER}) cm after the ticks stopped, still moving",
        holds=lambda rolled: rolled > 20,
        meaning="without the watchdog the robot rolls on after the ticks stop",
    ),
    Claim(
        says="A watchdog stops the **wheels**, it does not end the **node**",
        printed=rf"with the watchdog, at {_NUMBER} s:\n  nodes running: [^\n]*cautious_driver"
        rf"[^\n]*\n  the driver's last commands \(t, v\): \[\({_NUMBER}, 0\.0\), \({_NUMBER}, "
        rf"0\.0\), \({_NUMBER}, 0\.0\)\]\n  the wheels' duty cycles \(left, right\): \[0\. 0\.\]",
        holds=lambda: True,
        meaning="with the watchdog the driver still runs, sending zeros, the wheels at 0",
    ),
    Claim(
        says="The realistic encoders publish a little early or late, never much",
        printed=_GAPS_11,
        holds=lambda **n: all(
            20 < n[f"{wheel}_low"] < 33.3 < n[f"{wheel}_high"] < 50 for wheel in ("left", "right")
        ),
        meaning="every interval between two ticks is between 20 and 50 ms",
    ),
    Claim(
        says="No gap: the simulator never drops a message.",
        printed=_GAPS_11,
        holds=lambda **n: n["left_gaps"] == n["right_gaps"] == 0,
        meaning="stamp_gaps finds no gap in either encoder's stream",
    ),
    Claim(
        says="take out the left encoder's messages between 20.0 s and 20.8 s",
        printed=_DROPPED_11,
        holds=lambda dropped, start, end, silent: 19.9 < start < 20.0 and 20.8 < end < 20.9,
        meaning="stamp_gaps finds one gap, from just before 20.0 s to just after 20.8 s",
    ),
    Claim(
        says="a gap is a lone dot far above the dashed line, at the end of the silence",
        printed=_DROPPED_11,
        holds=lambda dropped, start, end, silent: silent > 10 * 50,
        meaning="the gap's silence is over ten times the 50 ms limit",
    ),
]

_WRAPS_10 = (
    r"odometry: (?P<up>\d+) jumps up \(0 -> 2 pi\), (?P<down>\d+) jumps down \(2 pi -> 0\); "
    rf"closest to east \(theta = 0\): {_NUMBER} deg\n\s+truth: (?P<true_up>\d+) jumps up "
    r"\(0 -> 2 pi\), (?P<true_down>\d+) jumps down \(2 pi -> 0\); closest to east \(theta = 0\): "
    rf"(?P<closest>{_NUMBER}) deg"
)
_WAIT_10 = r"wait:[^\n]*\n\s+every command 0\n\s+turned [-+]0 deg by odometry, [-+]0 deg really\n"
_STATES_10 = (
    rf"square:[^\n]*\n\s+driving at up to (?P<v>{_NUMBER}) m/s, \|omega\| {_NUMBER} to "
    rf"(?P<steer>{_NUMBER}) rad/s; turning on the spot at up to (?P<spot>{_NUMBER}) rad/s\n"
    rf"(?s:.*?)circle:[^\n]*\n\s+driving at up to {_NUMBER} m/s, \|omega\| "
    rf"(?P<circle_low>{_NUMBER}) to {_NUMBER} rad/s\n\s+turned (?P<circle_odometry>{_NUMBER}) deg "
    rf"by odometry, (?P<circle_truth>{_NUMBER}) deg really"
)

CLAIMS["10_bag_analysis"] = [
    Claim(
        says="Nine topics, all under the robot's namespace (`/duckiebot/`)",
        printed=r"topics:(?:\s+/duckiebot/\S+\s+\d+ msgs\s+: \S+\n){9}(?!\s+/)",
        holds=lambda: True,
        meaning="the mission's bag holds nine topics, all under /duckiebot/",
    ),
    Claim(
        says="about 30 per second per wheel",
        printed=rf"left_wheel_encoder_node/tick: \d+ readings, (?P<left>{_NUMBER}) per second"
        rf"[^\n]*\n[^\n]*right_wheel_encoder_node/tick: \d+ readings, (?P<right>{_NUMBER}) per "
        "second",
        holds=lambda left, right: 29 < left < 31 and 29 < right < 31,
        meaning="each wheel's ticks come 29 to 31 times a second",
    ),
    Claim(
        says="Far more wraps in the odometry's θ than the robot's turns across east!",
        printed=_WRAPS_10,
        holds=lambda up, down, true_up, true_down, closest: (
            up + down >= 10 and up + down >= 5 * (true_up + true_down)
        ),
        meaning="the odometry's theta jumps 10 times or more, five times as often as the truth's",
    ),
    Claim(
        says="The true heading wraps only twice on this run",
        printed=_WRAPS_10,
        holds=lambda up, down, true_up, true_down, closest: true_up + true_down == 2,
        meaning="the true theta jumps twice",
    ),
    Claim(
        says="during the stops both commands are 0 and x, y, θ stay flat",
        printed=_WAIT_10 + "(?s:.*?)" + _WAIT_10 + "(?s:.*?)" + _WAIT_10,
        holds=lambda: True,
        meaning="in each of the three waits every command is 0 and neither heading turns",
    ),
    Claim(
        says="the square is three legs driven forward (v > 0, with a small ω: the node steers) "
        "with turns on the spot between them (v = 0, ω ≠ 0)",
        printed=_STATES_10,
        holds=lambda **n: n["v"] > 0 and 0 < n["steer"] < n["spot"] / 3,
        meaning="in the square, driving steers with under a third of the turns' omega",
    ),
    Claim(
        says="in the circle the commands turn all the time, and by odometry θ sweeps through a "
        "whole turn",
        printed=_STATES_10,
        holds=lambda **n: n["circle_low"] > 0 and abs(n["circle_odometry"] + 360) < 20,
        meaning="every circle command turns, and the odometry turns -360 degrees",
    ),
    Claim(
        says="while on this realistic run the real robot turns less",
        printed=_STATES_10,
        holds=lambda **n: abs(n["circle_truth"]) < abs(n["circle_odometry"]) - 20,
        meaning="the real robot turns over 20 degrees less than odometry believes during the "
        "circle",
    ),
    Claim(
        says="the dashed robot drift away from the real one on the realistic robot",
        printed=rf"square: position gap\s+(?P<before>{_NUMBER}) ->\s+(?P<after>{_NUMBER}) cm",
        holds=lambda before, after: after > before + 10,
        meaning="odometry and truth part by more than 10 cm during the square",
    ),
    Claim(
        says="It computes offline exactly what your odometry node computed live during the run, "
        "so the two should agree",
        printed=rf"largest distance between the two, pose by pose: (?P<mm>{_NUMBER}) mm",
        holds=lambda mm: mm < 1,
        meaning="the replayed odometry is within 1 mm of the live one",
    ),
    Claim(
        says="(on this realistic run the truth wraps only twice",
        printed=_WRAPS_10,
        holds=lambda up, down, true_up, true_down, closest: true_up + true_down == 2,
        meaning="the true theta jumps twice",
    ),
    Claim(
        says="the calibrated robot replays your robot's ticks far closer than the realistic one",
        printed=rf"realistic: simulated over real travel (?P<rl>{_NUMBER}) \(left\), "
        rf"(?P<rr>{_NUMBER}) \(right\)[^\n]*\n\s*my_robot: simulated over real travel "
        rf"(?P<ml>{_NUMBER}) \(left\), (?P<mr>{_NUMBER}) \(right\)",
        holds=lambda rl, rr, ml, mr: (
            abs(ml - 1) < 0.02 and abs(mr - 1) < 0.02 and min(abs(rl - 1), abs(rr - 1)) > 0.1
        ),
        meaning="the calibrated robot's travel ratios are within 2 % of 1, the realistic one's "
        "over 10 % off",
    ),
    Claim(
        says="yet its odometry still drifts",
        printed=rf"my_robot\.json: {_NUMBER} s; ended {_NUMBER} cm from the start, odometry "
        rf"(?P<drift>{_NUMBER}) cm from the truth",
        holds=lambda drift: drift > 5,
        meaning="on the calibrated robot the odometry still ends over 5 cm from the truth",
    ),
]

CLAIMS["09_mission"] += [
    Claim(
        says="The node drives until its **odometry** says it is there, so the second gap can "
        "never be much smaller than the first.",
        printed=_REALISTIC_09,
        holds=lambda **n: n["home"] >= n["gap"] - n["believed"] - 0.2,
        meaning="the realistic robot ends at least as far from the start as its odometry is from "
        "the truth, less what the odometry believes is left",
    ),
]

CLAIMS["10_bag_analysis"] += [
    Claim(
        says="a virtual robot whose motors are weaker than the realistic one's",
        printed=rf"calibration_dead_band: (?P<dead_band>{_NUMBER})(?s:.*?)realistic: simulated "
        rf"over real travel (?P<left>{_NUMBER}) \(left\), (?P<right>{_NUMBER}) \(right\)",
        holds=lambda dead_band, left, right: left > 1.1 and right > 1.1,
        meaning="the realistic robot travels over 10 % further on the sample robot's commands",
    ),
    Claim(
        says="the wheels seldom turn at one command long enough to measure their speed at it",
        printed=rf"(?P<count>\d+) wheel commands on \S+ in (?P<seconds>{_NUMBER}) s, "
        rf"(?P<rate>{_NUMBER}) a second; (?P<held>\d+) of them held 1 s or more",
        holds=lambda count, seconds, rate, held: rate >= 10 and held <= 0.02 * count,
        meaning="the mission sends 10 commands a second or more, and 2 % of them or fewer are "
        "held 1 s",
    ),
    Claim(
        says="`calibration_turn_ratio` above is `nan` on a mission",
        printed=r"calibration_turn_ratio: nan\n",
        holds=lambda: True,
        meaning="the calibration prints its turn ratio as nan",
    ),
    Claim(
        says="headings that agree, paths that end far closer",
        printed=rf"realistic: simulated over real travel [^\n]*the paths end "
        rf"(?P<realistic_gap>{_NUMBER}) cm apart\n\s*my_robot: simulated over real travel "
        rf"[^\n]*heading change (?P<sim>{_NUMBER}) rad against (?P<real>{_NUMBER}); the paths "
        rf"end (?P<gap>{_NUMBER}) cm apart",
        holds=lambda realistic_gap, sim, real, gap: (
            abs(sim - real) < 0.2 and gap < 30 and realistic_gap > 4 * gap
        ),
        meaning="on the calibrated robot the heading changes agree within 0.2 rad and the paths "
        "end within 30 cm, four times closer than on the realistic one or more",
    ),
]

CLAIMS["11_to_the_robot"] += [
    Claim(
        says="the four nodes of `course.launch`, each in the robot's namespace `/duckiebot/`",
        printed=r"ran (?P<nodes>\d+) node\(s\) for [^\n]*\n"
        r"(?P<listed>(?:  /duckiebot/\w+ [^\n]*\n)+)",
        holds=lambda nodes, listed: nodes == 4 and listed.count("/duckiebot/") == 4,
        meaning="duckie run ran four nodes, all in /duckiebot/",
    ),
    Claim(
        says="The mission node is `required`: when it ended, the run ended",
        printed=r"/duckiebot/mission_node +(?P<how>ended \(required: the run ended with it\))",
        holds=lambda how: how.startswith("ended"),
        meaning="the required mission node ended and ended the run",
    ),
    Claim(
        says="and the wheels were stopped",
        printed=rf"the wheels were stopped: duty cycles (?P<left>{_NUMBER}), (?P<right>{_NUMBER})",
        holds=lambda left, right: left == 0 and right == 0,
        meaning="both wheels' duty cycles are 0 at the end of the run",
    ),
    Claim(
        says="The note says which node of the launch file did not run: `rosbag record`",
        printed=r"note: [^\n]*course\.launch, line \d+: node (?P<node>\w+) of package "
        r"(?P<package>\w+) is not in this project",
        holds=lambda node, package: (node, package) == ("record", "rosbag"),
        meaning="the one node left out is rosbag's record",
    ),
]

CLAIMS["11_to_the_robot"] += [
    Claim(
        says="Duckietown's base image with ROS Noetic, `dt-ros-commons`, tagged `daffy-arm64v8`",
        printed=r"ARG ARCH=arm64v8\n\s*\d+\s+ARG DISTRO=daffy\n\s*\d+\s+ARG "
        r"BASE_TAG=\$\{DISTRO\}-\$\{ARCH\}\n\s*\d+\s+ARG BASE_IMAGE=dt-ros-commons\n",
        holds=lambda: True,
        meaning="the Dockerfile's base image is dt-ros-commons, tagged daffy-arm64v8",
    ),
    Claim(
        says="It comes last, so that a new solution rebuilds only this last layer",
        printed=r"COPY \./deploy /code/course\n\s*\d+\s+ENV PYTHONPATH=/code/course[^\n]*\n"
        r"\s*\d+\s+ENV DUCKIE_SOLUTION=/code/course/solution\.py\n(?!\s*\d+\s)",
        holds=lambda: True,
        meaning="COPY ./deploy comes after every other COPY and RUN, followed only by two ENVs",
    ),
]

CLAIMS["02_ros_concepts"] = [
    Claim(
        says='"hello world 0" is missing',
        printed=r"I heard: hello world (?P<first>\d+)",
        holds=lambda first: first >= 1,
        meaning="the listener's first message is not the talker's first",
    ),
    Claim(
        says="The talker has sent its ten messages by now and returned",
        printed=r"I heard: hello world (?P<last>\d+)\naverage rate: (?P<rate>[\d.]+)",
        holds=lambda last, rate: last == 9 and rate == 2.0,
        meaning="the tenth message, hello world 9, was heard, at 2 messages a second",
    ),
    Claim(
        says="`rosnode list` no longer shows it, and `rostopic info` lists no publisher of chatter",
        printed=r"\$ rosnode list\n(?P<nodes>(?:/.*\n)+)\s*Type: std_msgs/String\s+Publishers:\s+"
        r"(?P<publishers>None)",
        holds=lambda nodes, publishers: "talker" not in nodes and "listener" in nodes,
        meaning="the finished talker is gone from the node list and from chatter's publishers",
    ),
]
