"""The paper's experimental constants, in one place (Yan, Ji & Chang 2024, Actuators 13:18).

Everything else that needs one of these numbers imports it from here, so that a user who changes the
protocol (more speeds, a wider acceptance band) changes it once.
"""
from __future__ import annotations

PAPER_SPEEDS: tuple[float, ...] = (1.0, 1.2, 1.4)  # m/s, the commanded speeds of Table 5 and Section 4.2
PAPER_LIFT_HEIGHT = 0.15  # m, foot lift H of the common trajectories (Section 2.3)
PAPER_WALK_DURATION = 10.0  # s, one comparison walk (Section 4.1: Tf = 10 s, Table 4)
PAPER_DISTANCE_M = 100.0  # m, one prototype walk (Section 4.2)

# Not the paper's: the project's acceptance band. A walk counts only if its mean speed is within this share
# of the command (±5 %), so that an energy saving cannot come from walking slower than asked.
SPEED_BAND = 0.05


def speed_within_band(mean_speed: float, command: float, band: float = SPEED_BAND) -> bool:
    """|v̄ − v_cmd| ≤ band · v_cmd: the walk kept the commanded speed. A Python bool even for numpy inputs (it
    goes into JSON and CSV rows)."""
    return bool(abs(mean_speed - command) <= band * command)


__all__ = ["PAPER_DISTANCE_M", "PAPER_LIFT_HEIGHT", "PAPER_SPEEDS", "PAPER_WALK_DURATION", "SPEED_BAND",
           "speed_within_band"]
