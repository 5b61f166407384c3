"""The experiment's reactive robot: a teleo-reactive rule list instead of a sequencer.

``situate demo --mode reactive`` runs it. There are no phases and no procedures. Every
cycle the controller reads what the robot senses, then goes down one ordered list of
rules (`Reactive.rules`). The first rule whose condition holds acts. Its action is a set
of standard skills (the same ones the sequenced robot uses) with their parameters. The
action stays on while the rule stays the first that applies (Nilsson's teleo-reactive
programs; a subsumption design arbitrated by priority would pick the same one).

A condition reads the senses and a little state the robot keeps:

- the stops said so far;
- whether it is out of the lab, or in a car;
- whether it has called a car on this floor, and pushed the floor's button in the car;
- where it is on a route leg;
- where the lab door's barcode was seen, and where it last got a metre away from (to tell
  it is stuck in the lab's clutter).

There is no phase counter: if a wheel slips, a person pushes the robot about, or a door
closes, the rule that fits the new situation takes over. Perception is always on:
`PERCEPTION` runs every cycle, because any rule may need any percept at any time.

Handling every task in one program means the conditions name the next stop: its floor,
and whether it is a lobby or the office. Adding a task kind means new rules, or new
terms in the old ones; `docs/experiment.md` counts them.

Beside the rule list: what the robot senses and keeps (`state`), its route follower
(`route`), its rules for cars (`car`) and its way through a door (`door`), mixed into
`Reactive`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import situate
from courier.geometry import SONARS, Pose
from courier.link import Link, OutOfTime
from courier.mission import (
    NORMAL,
    SKILLS,
    Mission,
    Stop,
)
from courier.reactive.car import CODE_ON_WALL_M, CarRider, wall_through
from courier.reactive.door import DoorPasser
from courier.reactive.route import (
    DOOR_STANDOFF,
    HOMED_M,
    PUSH_M,
    Action,
    RouteFollower,
    goto,
    turn,
)
from courier.reactive.state import UNSTICK_M, UNSTICK_S, Memory, RouteState, Senses

#: Skills every rule may read: on all the time.
PERCEPTION = (
    "fit_wall",
    "detect_intersection",
    "detect_door",
    "watch_openings",
    "identify_car",
    "locate_door",
)
#: What the controller reads every cycle.
PERCEPTS = (
    "odom",
    "sonar.range",
    "sonar.health",
    "barcodes",
    "floor",
    "arm",
    "speaker",
    "junction",
    "door",
    "opened",
    "car",
    "opening",
    "wall",
    "door_passed",
    "car_entered",
    "car_exited",
)
#: Parameters the rules set once, at the start: the sequenced robot's, and two of its own.
SETTINGS = {
    **NORMAL,
    ("leave_car", "distance"): 3.0,
    # Cars stay open 10 s or so: in before the door closes.
    ("enter_car", "speed"): 0.35,
    # Through a door to about the middle of the corridor beyond (as far as the sequenced robot
    # goes): stopped in the door's mouth, the hallway follower may take the door for the way.
    ("pass_door", "distance"): DOOR_STANDOFF + 1.1,
}
#: Homing to push a call button, the robot goes this last bit without runaway, m.
BUTTON_LAST_M = 1.0
#: Having given up on a door, the robot leaves it alone this long, s.
DOOR_AGAIN_S = 40.0
#: The lab door barcode's wall is noted from the fits ahead through the barcode, seen from
#: this far to this far (m; the last `LAB_WALL_FITS` of them): nearer, the few echoes round the
#: barcode are the door's jamb as much as the wall, and a line fitted through them may be
#: the jamb's.
LAB_WALL_FROM_M = 1.5
LAB_WALL_SEEN_M = 3.0
LAB_WALL_FITS = 50
#: Rules that move the robot about in the lab: under one of them, or following a corridor on
#: a route leg, not 1 m from where it was this long ago, the robot is stuck (clutter, a corner,
#: wedged in a doorway), s. (Homing on the call button and the route's other steps may take as
#: long legitimately: slowly up to the button, waiting at a door.)
MOVING_RULES = ("search", "home on lab door", "to lab door")
STUCK_S = 60.0
#: Following a corridor and no new way made for `STUCK_S`, the robot goes back to where it was
#: when it had made this much less way (m), for at most this long (s), then follows on.
TRAIL_BACK_M = 1.0
TRAIL_UNSTICK_S = 30.0
#: Back to where a barcode was seen (the lab door's, a call button's): up to this far short of
#: it, m, for at most this long, s.
SIGHTING_SHORT_M = 1.5
SIGHTING_S = 60.0


class Reactive(CarRider, DoorPasser, RouteFollower, Link):
    """The teleo-reactive controller: every cycle, the first applicable rule acts."""

    def __init__(
        self, robot: situate.Robot, mission: Mission, stops: Sequence[Stop], **kw: Any
    ) -> None:
        # The skills are switched as the sequenced robot's are (`use`), by the rules.
        super().__init__(robot, normal=SETTINGS, **{**kw, "mode": "sequenced"})
        self.m = mission
        self.stops = list(stops)
        self.mem = Memory()
        self.action_key: Any = None
        self.rule_name = ""
        #: When the rule in charge took over (simulated time).
        self.rule_since = 0.0
        #: Rule changes (the drive's winner changing), for the experiment.
        self.switches = 0
        #: Cycles run and sensed (`sense`; DELIVER_DEBUG prints them with the round trips).
        self.cycles = 0
        self.rules: list[tuple[str, Callable[[Senses], bool], Callable[[Senses], Action]]] = [
            ("done", self.all_made, lambda s: Action(())),
            ("say", self.at_stop, self.say_message),
            ("leave car", self.car_arrived, self.leave_car),
            ("ride", self.riding, self.ride),
            ("push floor", self.in_car_to_press, self.push_floor),
            ("enter car", self.car_opened, self.enter_car),
            ("wait for car", self.waiting_for_car, self.wait_for_car),
            ("push call", self.at_call_button, self.push_call),
            ("unstick", self.stuck, self.get_unstuck),
            ("home on button", self.button_in_view, self.home_on_button),
            ("to office", self.office_route_applies, self.route_action),
            ("to lobby", self.lobby_route_applies, self.route_action),
            ("look for button", self.off_start_floor, self.look_for_button),
            ("pass lab door", self.at_lab_door, self.pass_door_action),
            ("home on lab door", self.lab_door_in_view, self.home_on_lab_door),
            ("to lab door", self.lab_door_known, self.to_lab_door),
            ("search", lambda s: True, self.wander_about),
        ]

    # ----- the senses --------------------------------------------------------------------

    async def sense(self) -> Senses:
        """Runs one cycle and reads every percept, in one round trip and one request.

        The percepts are one snapshot (`Link.snapshot`): all of the cycle just run. A skill
        that faulted since the last look is switched on again (`Link.on_fault`).
        """
        for fault in self.take_faults():
            await self.on_fault(fault)
        self.send("step", cycles=1)
        self.cycles += 1
        snapshot = self.snapshot(*PERCEPTS)
        await self.flush()
        for attempt in range(3):
            try:
                v = await snapshot.values()
            except situate.Interrupted:  # asked while the cycle restarted: ask again
                if attempt == 2:
                    raise
                self.t_stale = True
            if not self.t_stale:
                break
            # The step was cut short by a stuck body (`flush`): read afresh, and the time.
            snapshot = self.snapshot(*PERCEPTS)
            await self.now()
        o = v["odom"] or {"x": 0.0, "y": 0.0, "theta": 0.0}
        b = v["barcodes"] or {"ids": [], "bearing": [], "distance": []}
        codes = {
            int(i): (float(a), float(d))
            for i, a, d in zip(b["ids"], b["bearing"], b["distance"], strict=False)
        }
        return Senses(
            t=self.t,
            pose=Pose(float(o["x"]), float(o["y"]), float(o["theta"])),
            sonar=[float(r) for r in (v["sonar.range"] or [4.0] * SONARS)],
            barcodes=codes,
            floor=int(v["floor"] if v["floor"] is not None else self.m.start_floor),
            presses=int((v["arm"] or {}).get("presses", 0)),
            said=int((v["speaker"] or {}).get("count", 0)),
            junction=dict(v["junction"] or {}),
            door=dict(v["door"] or {}),
            opened=dict(v["opened"] or {}),
            car=int(v["car"] or 0),
            opening=dict(v["opening"] or {}),
            wall=dict(v["wall"] or {}),
            door_passed=bool(v["door_passed"]),
            car_entered=bool(v["car_entered"]),
            car_exited=bool(v["car_exited"]),
            dead=int((v["sonar.health"] or {}).get("mask", 0)),
        )

    # ----- the next stop -------------------------------------------------------------------

    def stop(self) -> Stop:
        """The next stop (the last one once all are made)."""
        return self.stops[min(self.mem.made, len(self.stops) - 1)]

    def stop_floor(self) -> int:
        """The floor of the next stop."""
        return self.stop()[1]

    def button(self, floor: int) -> int:
        """The call button's barcode on ``floor``."""
        return self.m.lobbies.get(floor, self.m.call_button_barcode)

    # ----- conditions (each reads the senses and the memory only) ---------------------------

    def all_made(self, s: Senses) -> bool:
        """Every stop made."""
        return self.mem.made >= len(self.stops)

    def at_stop(self, s: Senses) -> bool:
        """At the next stop's place: in front of its floor's button, or in the office."""
        kind, floor = self.stop()
        if self.mem.in_car or s.floor != floor:
            return False
        if kind == "office":
            return self.mem.in_office
        return s.sees(self.button(floor), HOMED_M + 0.3)

    def button_in_view(self, s: Senses) -> bool:
        """Out of the lab, this floor's call button in view, and the way goes by it."""
        # The button of this floor, once on a floor where it matters: to call a car, or
        # to say the message, or to start the route to the office from.
        if self.mem.in_car or not self.mem.out_of_lab or not s.sees(self.button(s.floor)):
            return False
        if s.floor == self.m.start_floor and "lab_to_lobby" not in self.mem.legs_done:
            # Seeing the button ends the way to the lobby, wherever the route hints were.
            self.mem.legs_done.add("lab_to_lobby")
            self.mem.route = None
        self.mem.lobby_seen_on = s.floor
        kind, floor = self.stop()
        if kind == "office" and s.floor == floor:
            # The office route starts in front of the button, and then leaves it behind.
            on_route = self.mem.route is not None and self.mem.route.leg == self.office_leg()
            return (
                self.office_leg() == "button_to_office" and not on_route and not self.near_button(s)
            )
        return True

    def stuck(self, s: Senses) -> bool:
        """Unsticking: not 1 m from one place for long while moving about (see `remember`)."""
        m = self.mem
        if m.unstick_to is None or m.in_car:
            return False
        gx, gy = m.unstick_to
        if s.t - m.unstick_since > m.unstick_for or math.hypot(s.pose.x - gx, s.pose.y - gy) < 0.2:
            m.unstick_to, m.moved_from = None, None
            return False
        return True

    def office_route_applies(self, s: Senses) -> bool:
        """On the office's floor, on the route to the office (or at its start)."""
        kind, floor = self.stop()
        if kind != "office" or self.mem.in_car or s.floor != floor or self.mem.in_office:
            return False
        leg = self.office_leg()
        if self.mem.route is None or self.mem.route.leg != leg:
            if leg == "button_to_office" and not self.near_button(s):
                return False
            # The leg's headings are from square in front of the button: the wall's normal.
            # From the button, the route's turns are from square in front of it: up to the
            # button first, where its wall is what the wall fitter sees, then back.
            stage = "approach" if leg == "button_to_office" else "start"
            self.mem.route = RouteState(leg, stage=stage)
        return True

    def office_leg(self) -> str:
        """The route to the office: from the goal floor's button, or (older maps) the car."""
        return "button_to_office" if "button_to_office" in self.m.route else "car_to_office"

    def lobby_route_applies(self, s: Senses) -> bool:
        """Out of the lab, on the start floor, before the lobby."""
        if not self.mem.out_of_lab or s.floor != self.m.start_floor:
            return False
        if "lab_to_lobby" in self.mem.legs_done or self.mem.in_car:
            return False
        if self.mem.route is None:
            # The leg begins facing out of the lab door.
            self.mem.route = RouteState("lab_to_lobby", heading=self.mem.passed_heading)
        return True

    def off_start_floor(self, s: Senses) -> bool:
        """Out of the lab and out of any car (somewhere in a lobby or corridor)."""
        return self.mem.out_of_lab and not self.mem.in_car

    def at_lab_door(self, s: Senses) -> bool:
        """In the lab, in front of the lab door's barcode (or lining up, or passing the door)."""
        m = self.mem
        if s.t - m.door_given_up_at < DOOR_AGAIN_S:
            return False
        return not m.out_of_lab and (
            m.door_goal is not None
            or m.door_stage == "line up"
            or s.sees(self.m.lab_door_barcode, HOMED_M)
        )

    def lab_door_known(self, s: Senses) -> bool:
        """In the lab, the lab door's barcode seen before (out of view now)."""
        if s.t - self.mem.door_given_up_at < DOOR_AGAIN_S:
            return False
        return not self.mem.out_of_lab and self.mem.lab_door_at is not None

    def lab_door_in_view(self, s: Senses) -> bool:
        """In the lab, the lab door's barcode in view."""
        if s.t - self.mem.door_given_up_at < DOOR_AGAIN_S:
            return False
        return not self.mem.out_of_lab and s.sees(self.m.lab_door_barcode)

    # ----- helpers of conditions -----------------------------------------------------------

    def near_button(self, s: Senses) -> bool:
        """About 1 m in front of this floor's call button, facing it."""
        b = s.barcodes.get(self.button(s.floor))
        return b is not None and b[1] <= HOMED_M and abs(b[0]) < 0.25

    # ----- actions ---------------------------------------------------------------------------

    def say_message(self, s: Senses) -> Action:
        """Says the message."""
        return Action(("say",), {("say", "message"): self.m.message}, key=("say", self.mem.made))

    def get_unstuck(self, s: Senses) -> Action:
        """Drives to where unsticking goes (`watch_progress`).

        Towards where the sonars read farthest (out of a corner, off clutter), or back along
        a route leg's way, round what is in the way.
        """
        m = self.mem
        assert m.unstick_to is not None
        gx, gy = m.unstick_to
        key = ("unstick", m.unstick_since)
        if m.unstick_back:
            return goto(gx, gy, key, avoid=True)
        return goto(gx, gy, key, reverse_within=1.5)

    def home_on_button(self, s: Senses) -> Action:
        """Homes on this floor's call button (to push it, or to stand 1 m from it)."""
        code = self.button(s.floor)
        calling = s.floor != self.stop_floor()
        stop = PUSH_M - 0.05 if calling else 1.0
        # The last metre to push it, without runaway, as the sequenced robot: it keeps the
        # robot 0.3 m off the wall, which it must come within 0.2 m of (come aslant, say from
        # a car that did not open, it held the robot short for a minute at a time).
        b = s.barcodes.get(code)
        last = calling and b is not None and b[1] < BUTTON_LAST_M
        return Action(
            ("track_barcode", "home") if last else ("runaway", "track_barcode", "home"),
            {("track_barcode", "id"): code, ("home", "stop_distance"): stop},
            key=("home", code, stop, last),
        )

    def look_for_button(self, s: Senses) -> Action:
        """Back to where the call button was last seen from near, else looks round for it."""
        seen_from = self.mem.button_seen_from.get(s.floor)
        if (
            seen_from is not None
            and math.hypot(s.pose.x - seen_from.x, s.pose.y - seen_from.y) > 0.3
        ):
            key = ("back to button", s.floor, seen_from.x, seen_from.y)
            return goto(seen_from.x, seen_from.y, key, avoid=True)
        at = self.mem.button_at.get(s.floor)
        if at is not None:
            # Seen from farther only (someone stepped in front of it since, say): towards it.
            back = self.to_sighting(s, *at, "button")
            if back is not None:
                return back
            del self.mem.button_at[s.floor]
        return self.wander_about(s)

    def to_sighting(
        self, s: Senses, at: tuple[float, float], seen_from: tuple[float, float], what: str
    ) -> Action | None:
        """Back towards where a barcode was seen (``at``, from ``seen_from``), then faces it.

        Up to `SIGHTING_SHORT_M` short of it along the line it was seen on, for at most
        `SIGHTING_S` (since the rule in charge took over). None once there and facing it:
        not in view from there, it is not where it was seen (or hidden); the caller forgets it.
        """
        (bx, by), (fx, fy) = at, seen_from
        far = math.hypot(bx - fx, by - fy)
        short = min(SIGHTING_SHORT_M, far)
        gx, gy = bx - short * (bx - fx) / max(far, 1e-6), by - short * (by - fy) / max(far, 1e-6)
        if math.hypot(s.pose.x - gx, s.pose.y - gy) > 0.3 and s.t - self.rule_since < SIGHTING_S:
            return goto(gx, gy, (f"to {what}", bx, by), avoid=True)
        off = s.pose.bearing_to(bx, by)
        if abs(off) > 0.1:
            return turn(off, (f"face {what}", bx, by), s.t)
        return None

    def to_lab_door(self, s: Senses) -> Action:
        """Back towards where the lab door's barcode was seen, short of it, then faces it."""
        m = self.mem
        assert m.lab_door_at is not None
        back = self.to_sighting(s, m.lab_door_at, m.lab_door_from, "lab door")
        if back is not None:
            return back
        # There, facing it, and not in view: forget it (the search takes over).
        m.lab_door_at = None
        return Action(("runaway",), key="lab door not here")

    def home_on_lab_door(self, s: Senses) -> Action:
        """Homes on the lab door's barcode."""
        return Action(
            ("runaway", "avoid", "track_barcode", "home"),
            {("track_barcode", "id"): self.m.lab_door_barcode, ("home", "stop_distance"): 0.9},
            key="home lab door",
        )

    def wander_about(self, s: Senses) -> Action:
        """Wanders (avoiding obstacles), turning round in place now and then."""
        # The reader looks ahead only: a turn in place first, and again now and then,
        # wandering between (timed from when the rule in charge last changed).
        since = s.t - self.rule_since
        leg = int(since // 25)
        if since % 25 < 9:
            return Action(
                ("runaway", "avoid", "turn"), {("turn", "angle"): 2 * math.pi}, key=("look", leg)
            )
        return Action(
            ("runaway", "avoid", "wander"),
            {("wander", "seed"): (self.seed * 7919 + leg) % (1 << 31)},
            key=("wander", leg),
        )

    def remember(self, s: Senses) -> None:
        """Updates the little state from this cycle's senses (events the skills report)."""
        m = self.mem
        b = s.barcodes.get(self.button(s.floor))
        if b is not None and not m.in_car:
            if b[1] < 1.6 and abs(b[0]) < 0.3:
                m.button_seen_from[s.floor] = s.pose
            m.button_at[s.floor] = (s.pose.seen_at(b[0], b[1]), (s.pose.x, s.pose.y))
        self.watch_progress(s)
        d = s.barcodes.get(self.m.lab_door_barcode)
        if d is not None and not m.out_of_lab:
            m.lab_door_at = s.pose.seen_at(d[0], d[1])
            m.lab_door_from = (s.pose.x, s.pose.y)
            near = LAB_WALL_FROM_M <= d[1] <= LAB_WALL_SEEN_M
            fitted = wall_through(d, s.wall, CODE_ON_WALL_M) if near else None
            if fitted is not None:
                m.lab_door_walls = [*m.lab_door_walls[-LAB_WALL_FITS + 1 :], s.pose.theta + fitted]
        made = s.said - m.said_at_start
        if made > m.made:
            m.made = made
        self.remember_car(s)
        lab_door = m.door_goal
        if self.rule_name == "pass lab door" and lab_door is not None and self.through_door(s):
            # The leg to the lobby begins facing out through the door: the heading the robot
            # faced to pass it (as the sequenced robot), not the one it ended with (centring
            # between the jambs, or avoiding someone beyond, turns it).
            m.passed_heading, m.out_of_lab = lab_door[2], True

    def watch_progress(self, s: Senses) -> None:
        """Notes where the robot got to; stuck for long under a moving rule, where to go.

        Following a corridor on a route leg, what counts is the way made along it: no new way
        for `STUCK_S` (people in the way; or, pushed round them, into a room's doorway, where
        the hallway follower goes round the room), the robot goes back along its trail.
        """
        m, p = self.mem, s.pose
        r = m.route
        following = self.following(s) and not m.in_car
        if following and r is not None and r.trail:
            if m.unstick_to is None and s.t - r.progress_at > STUCK_S:
                self.unstick_back_along(s, r)
            return
        moving = (self.rule_name in MOVING_RULES or following) and not m.in_car
        if (
            not moving
            or m.moved_from is None
            or math.hypot(p.x - m.moved_from[1], p.y - m.moved_from[2]) > 1.0
        ):
            if m.unstick_to is None:
                m.moved_from = (s.t, p.x, p.y)
            return
        if m.unstick_to is None and s.t - m.moved_from[0] > STUCK_S:
            self.unstick_freest(s)

    def unstick_freest(self, s: Senses) -> None:
        """Unsticks towards the freest way, up to `UNSTICK_M`.

        The freest way: the sonar whose own and neighbours' nearest echo is farthest.
        """
        m, p = self.mem, s.pose
        free = [min(s.sonar[(i + k) % SONARS] for k in (-1, 0, 1)) for i in range(SONARS)]
        i = max(range(SONARS), key=lambda j: free[j])
        go = max(0.3, min(UNSTICK_M, free[i] - 0.6))
        a = p.theta + 2 * math.pi * i / SONARS
        m.unstick_to, m.unstick_since = p.ahead(go, a), s.t
        m.unstick_for, m.unstick_back = UNSTICK_S, False
        if self.debug:
            print(f"[{s.t:7.1f} s]   stuck: {go:.1f} m towards {math.degrees(a):.0f} deg")

    def unstick_back_along(self, s: Senses, r: RouteState) -> None:
        """Unsticks back along the leg's trail, to where the way made was `TRAIL_BACK_M` less.

        That is a place the robot stood in the corridor, on the way: not the freest way,
        which in a corridor blocked by people is often a room's door.
        """
        m, p = self.mem, s.pose
        r.progress_at = s.t  # the way gets another `STUCK_S` after this
        back = [(x, y) for went, x, y in r.trail if went <= r.trail[-1][0] - TRAIL_BACK_M]
        gx, gy = back[-1] if back else r.trail[0][1:]
        if math.hypot(p.x - gx, p.y - gy) < 0.3:  # stuck where the leg began: the freest way
            self.unstick_freest(s)
            return
        m.unstick_to, m.unstick_since = (gx, gy), s.t
        m.unstick_for, m.unstick_back = TRAIL_UNSTICK_S, True
        if self.debug:
            print(f"[{s.t:7.1f} s]   no way made: back along the way to ({gx:.1f}, {gy:.1f})")

    def following(self, s: Senses) -> bool:
        """On a route leg, following a corridor (not homing on a barcode, nor at a door)."""
        r = self.mem.route
        if r is None or self.rule_name not in ("to office", "to lobby") or r.stage != "follow":
            return False
        steps = self.m.route.get(r.leg, [])
        return r.step < len(steps) and bool(steps[r.step].get("follow"))

    # ----- the loop -----------------------------------------------------------------------------

    async def apply(self, name: str, action: Action, s: Senses) -> None:
        """Switches to ``action`` when it is new (its key changed): skills and parameters."""
        key = (name, action.key)
        if key == self.action_key:
            return
        if self.rule_name != name:
            self.switches += 1
            self.rule_since = s.t
            # The rule in charge, as the narrative's phase (`situate demo` notes the last).
            await self.phase(1 + [n for n, _, _ in self.rules].index(name), f"rule {name!r}")
        if self.debug:
            await self.say(f"  {action.key}")
        self.action_key, self.rule_name = key, name
        for (skill, param), value in action.params.items():
            await self.set(skill, param, value)
        await self.use(*PERCEPTION, *action.skills, restart=action.skills)

    async def run_task(self) -> None:
        """Runs the rule list every cycle until every stop is made (or the time is up)."""
        for (skill, param), value in SETTINGS.items():
            await self.set(skill, param, value)
        await self.set("identify_car", "first_id", self.m.car_barcode_first)
        await self.set("identify_car", "cars", self.m.cars)
        self.send("deactivate", skills=sorted(SKILLS))
        await self.keep_on_the_rest(SKILLS)
        await self.use(*PERCEPTION)
        self.t_stale = True
        await self.now()  # the clock and the cycle's period: `step` advances `t` by it
        s = await self.sense()
        self.mem.said_at_start = s.said
        self.mem.presses_seen = s.presses
        traced = 0.0
        while True:
            s = await self.sense()
            if self.trace is not None and s.t >= traced + 0.25:  # DELIVER_TRACE: the true pose
                traced = s.t
                await self._trace()
            self.remember(s)
            if self.mem.made >= len(self.stops):
                break
            if s.t >= self.limit_s:
                raise OutOfTime(f"the mission's {self.limit_s:.0f} s are up")
            for name, applies, act in self.rules:
                if applies(s):
                    await self.apply(name, act(s), s)
                    break
        await self.use()
        await self.flush()
        await self.say(f"mission complete ({self.switches} rule switches)")
        if self.debug:
            n, trips, requests = max(self.cycles, 1), self.round_trips, self.requests
            print(
                f"round trips to the robot: {trips} ({trips / n:.2f} a cycle),"
                f" requests: {requests} ({requests / n:.2f} a cycle), cycles: {self.cycles}"
            )
