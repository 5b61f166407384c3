"""The reactive robot's way through a door beside a barcode (the lab's, the office's).

To the opening beside the barcode, square to it, through; mixed into the reactive controller
(`rules.Reactive`), whose rule "pass lab door" acts by `DoorPasser.pass_door_action`.
"""

from __future__ import annotations

import math

from courier.geometry import Pose, mean_heading, wrap
from courier.mission import DOOR_BESIDE_BARCODE_M, DOOR_WAIT_S
from courier.reactive.route import DOOR_STANDOFF, Action, goto, turn
from courier.reactive.state import Memory, Senses

#: A door placed anew is the same door only this near where it was first placed (m), and
#: facing this near the same way (rad).
DOOR_MOVED_M = 1.0
DOOR_TURNED_RAD = 0.8
#: A door is placed from the opening seen in every cycle of the last `DOOR_FIX_S` (s), all
#: within `DOOR_FIX_M` (m) of their mean: one cycle's estimate may be a sonar's lost echo, or a
#: dead sonar not yet found (the sonar filter needs a second or so of moving to tell).
DOOR_FIX_S = 0.5
DOOR_FIX_M = 0.25
#: Stopped in a doorway, the robot goes on once the way ahead is clear this far (m; its
#: radius and 0.9 m), or after this long (s), at most this many times.
DOOR_CLEAR_M = 1.15
DOOR_BLOCKED_S = 10.0
DOOR_PUSHES = 3
#: The lab door is in its barcode's wall: an opening whose line is farther than this from the
#: barcode (m), or whose near jamb is farther along the wall than `DOOR_BESIDE_BARCODE_M` (the
#: sequenced robot's bound), is some other way (the corridor seen from the doorway, say).
DOOR_OFF_BARCODE_WALL_M = 0.5
#: A robot that homed on the lab door's barcode aslant, into the doorway, lines up this far
#: square in front of the barcode (m).
LINE_UP_M = 1.0
#: A door is square to its wall: placed farther off the lab door barcode's wall than this,
#: it is placed aslant (the sequenced robot's bound for a wall square to a corridor), rad.
DOOR_SQUARE_RAD = math.radians(25)


class DoorPasser:
    """Passes the door beside a barcode; mixed into the reactive controller.

    It uses the controller's memory (the door's stage and fixes, `state.Memory`) and debug flag.
    """

    mem: Memory
    debug: bool

    def pass_door_action(self, s: Senses) -> Action:
        """In front of a door beside a barcode: to the opening, face it, through."""
        m = self.mem
        if m.door_stage == "line up" and (step := self.lining_up(s)) is not None:
            return step
        if m.door_stage == "blocked":
            if s.sonar[0] < DOOR_CLEAR_M and s.t - m.door_blocked_at < DOOR_BLOCKED_S:
                return Action(("runaway",), key=("door blocked", m.door_pushes))
            m.door_stage = "pass"
        if m.door_stage == "check":
            # In front of it and facing it: the opening straight ahead, else placed anew
            # from here (seen from aside, the first fix is rough).
            o = s.opening
            lateral = abs(float(o.get("y", 0.0))) if o.get("seen") else 0.0
            if lateral > 0.15 and m.door_fixes < 3:
                m.door_place_anew()
            else:
                m.door_stage = "pass"
        if m.door_goal is None:
            o = s.opening
            if not o.get("seen") or float(o.get("width", 0.0)) < 0.6:
                # Square to the wall the barcode is on: the door finder looks along it.
                if s.wall.get("seen") and abs(float(s.wall["normal"])) > 0.1:
                    off = float(s.wall["normal"])
                    return turn(off, "square", s.t, every=5)
                return self.wait_for_opening(s)
            goal = self.steady_door(s)
            if goal is None:
                return self.wait_for_opening(s)
            # Checked against the lab door's barcode in the lab only: out of it, this is the
            # office's door, which this check has not been tried on.
            at = m.lab_door_at if not m.out_of_lab else None
            walls = m.lab_door_walls if not m.out_of_lab else []
            if (at is not None and not beside_barcode(goal, float(o.get("width", 0.0)), at)) or (
                walls and abs(wrap(goal[2] - mean_heading(walls))) > DOOR_SQUARE_RAD
            ):
                # Not the lab door's opening, or placed aslant: homed aslant into the doorway,
                # the robot sees the corridor beyond, say, or the door's jambs askew. It lines
                # up square in front of the barcode, once.
                if self.debug:
                    print(f"[{s.t:7.1f} s]   an opening off barcode {m.lab_door_at}: not its door")
                if walls and not m.door_lined_up:
                    m.door_lining_up()
                    if (step := self.lining_up(s)) is not None:
                        return step
                return self.wait_for_opening(s)
            first = m.door_first
            if (
                m.door_after_pass
                and first is not None
                and (
                    math.hypot(goal[0] - first[0], goal[1] - first[1]) > DOOR_MOVED_M
                    or abs(wrap(goal[2] - first[2])) > DOOR_TURNED_RAD
                )
            ):
                # Placed anew from the doorway (stopped short in it), the door is where it was
                # placed from in front: an opening elsewhere is another (the corridor seen
                # from the doorway, a door across it), and going through it is no way in.
                return self.wait_for_opening(s)
            m.door_placed(goal)
            gx, gy, heading = goal
        else:
            gx, gy, heading = m.door_goal
        if m.door_stage == "goto":
            if math.hypot(s.pose.x - gx, s.pose.y - gy) < 0.12:
                m.door_stage = "face"
            else:
                return goto(gx, gy, ("door goto", m.door_goal))
        if m.door_stage == "face":
            off = s.pose.turn_to(heading)
            if abs(off) > 0.06:
                return turn(off, ("door face", m.door_goal), s.t)
            m.door_stage = "check"
            return Action(("runaway",), key=("door check", m.door_goal))
        return Action(("runaway", "pass_door"), key=("door pass", m.door_goal, m.door_pushes))

    def lining_up(self, s: Senses) -> Action | None:
        """The line-up's next action; once lined up (None), the stage ends, and not again."""
        step = self.line_up_on_lab_door(s)
        if step is None:
            self.mem.door_line_up_done()
        return step

    def line_up_on_lab_door(self, s: Senses) -> Action | None:
        """To `LINE_UP_M` square in front of the lab door's barcode, facing its wall.

        The wall is the mean of its fits (`remember`). None once there (or with no fit).
        """
        m = self.mem
        if m.lab_door_at is None or not m.lab_door_walls:
            return None
        n = mean_heading(m.lab_door_walls)
        bx, by = m.lab_door_at
        tx, ty = bx - LINE_UP_M * math.cos(n), by - LINE_UP_M * math.sin(n)
        if math.hypot(s.pose.x - tx, s.pose.y - ty) > 0.12:
            return goto(tx, ty, ("line up", round(tx, 2), round(ty, 2)))
        off = s.pose.turn_to(n)
        if abs(off) > 0.06:
            return turn(off, ("line up face", round(n, 2)), s.t)
        return None

    def steady_door(self, s: Senses) -> tuple[float, float, float] | None:
        """The door from the opening seen now, if seen steadily (`DOOR_FIX_S`, `DOOR_FIX_M`).

        The point `DOOR_STANDOFF` in front of the opening and the heading through it, in the
        odometry frame: their mean over the last cycles, each of which saw the opening near
        it. None while the last cycles disagree (a lost echo, a dead sonar not yet found,
        someone walking by), or have not seen it long enough.
        """
        m, o = self.mem, s.opening
        normal, cx, cy = float(o["normal"]), float(o["x"]), float(o["y"])
        ax, ay = cx - DOOR_STANDOFF * math.cos(normal), cy - DOOR_STANDOFF * math.sin(normal)
        now = (*s.pose.from_robot(ax, ay), s.pose.theta + normal)
        m.door_seen = [(t, g) for t, g in m.door_seen if s.t - t < DOOR_FIX_S + 0.05]
        m.door_seen.append((s.t, now))
        # A cycle without the opening breaks the run (`pass_door_action` calls this only
        # when it sees one): the time of each seen must follow the one before.
        times = [t for t, _ in m.door_seen]
        if times[-1] - times[0] < DOOR_FIX_S - 0.05 or any(
            b - a > 0.15 for a, b in zip(times, times[1:], strict=False)
        ):
            return None
        n = len(m.door_seen)
        gx = sum(g[0] for _, g in m.door_seen) / n
        gy = sum(g[1] for _, g in m.door_seen) / n
        gh = mean_heading(g[2] for _, g in m.door_seen)
        if any(math.hypot(g[0] - gx, g[1] - gy) > DOOR_FIX_M for _, g in m.door_seen):
            return None
        m.door_seen = []
        return (gx, gy, gh)

    def wait_for_opening(self, s: Senses) -> Action:
        """Stands in front of the door until it opens; gives up after `DOOR_WAIT_S`."""
        m = self.mem
        if m.door_waiting_since is None:
            m.door_waiting_since = s.t
        elif s.t - m.door_waiting_since > DOOR_WAIT_S:
            # No door here after all (or shut for long): leave it, look again later.
            m.door_given_up(s.t)
        return Action(("runaway",), key="wait for opening")

    def through_door(self, s: Senses) -> bool:
        """Passed (`door_passed`) and truly beyond the door's line (not stopped in it)."""
        m = self.mem
        if not s.door_passed or m.door_stage != "pass" or m.door_goal is None:
            return False
        went = Pose(*m.door_goal).along(s.pose.x, s.pose.y)
        if went >= DOOR_STANDOFF + 0.4:
            m.door_through()
            return True
        if went >= DOOR_STANDOFF - 0.3 and m.door_pushes < DOOR_PUSHES:
            # Stopped in the doorway: someone beyond, not the jambs (as the sequenced robot
            # reads it). Placed anew from in there, the door would be anything; so the robot
            # waits for the way ahead to clear, and goes on.
            m.door_blocked(s.t)
            return False
        # Stopped short (someone in the way, a jamb): place the door anew and go again.
        m.door_stopped_short()
        return False


def beside_barcode(
    goal: tuple[float, float, float], width: float, code: tuple[float, float]
) -> bool:
    """Whether a door placed at ``goal`` is beside the barcode at ``code`` (odometry).

    ``goal`` is the point `DOOR_STANDOFF` in front of the opening and the heading through it.
    The barcode is on the opening's line (`DOOR_OFF_BARCODE_WALL_M`), and the opening's near
    jamb is within `DOOR_BESIDE_BARCODE_M` of it along the wall (docs/maps.md: 0.1 to 0.6 m).
    """
    # The opening's centre, facing through it.
    door = Pose(*Pose(*goal).ahead(DOOR_STANDOFF), goal[2])
    across = door.along(code[0], code[1])  # off the opening's line
    along = abs(door.across(code[0], code[1])) - width / 2  # along it, past the near jamb
    return abs(across) < DOOR_OFF_BARCODE_WALL_M and along < DOOR_BESIDE_BARCODE_M
