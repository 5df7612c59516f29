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

import re
from dataclasses import dataclass
from typing import Callable, Dict, List, Mapping, Optional

__all__ = ["CLAIMS", "Claim", "check_claim", "markdown_text"]


@dataclass(frozen=True)
class Claim:
    """A sentence of a notebook about its own figures or printouts, and the numbers behind it.

    Attributes:
        says: words of the notebook's markdown that make the claim, as written (spaces and
            line breaks may differ).
        printed: a regular expression with named groups, searched in everything the notebook's
            code cells printed; each group is read as a number.
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


def check_claim(claim: Claim, markdown: str, printed: str) -> Optional[str]:
    """Why ``claim`` does not hold in a notebook's text and printouts, or None when it holds."""
    if _words(claim.says) not in _words(markdown):
        return f"the text no longer says {claim.says!r}: update or remove its claim"
    found = re.search(claim.printed, printed)
    if found is None:
        return f"nothing printed matches {claim.printed!r}, the numbers behind {claim.says!r}"
    numbers = {name: float(value) for name, value in found.groupdict().items()}
    if not claim.holds(**numbers):
        shown = ", ".join(f"{name} = {value:g}" for name, value in numbers.items())
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
