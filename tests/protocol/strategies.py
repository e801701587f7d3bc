"""Hypothesis strategies for protocol messages, masks and states (wire units)."""

from __future__ import annotations

from hypothesis import strategies as st

from odohil.protocol.nomad import messages as m
from odohil.protocol.nomad.framing import MAX_LEN, Packet
from odohil.protocol.nomad.state import RobotState, StateMask

s16 = st.integers(-0x7FFF, 0x7FFF)
u16 = st.integers(0, 0xFFFF)
u8 = st.integers(0, 0xFF)


def _three(cls: type, word: st.SearchStrategy[int]) -> st.SearchStrategy[m.Request]:
    return st.builds(cls, word, word, word)


requests: st.SearchStrategy[m.Request] = st.one_of(
    _three(m.Ac, u16),
    _three(m.Sp, u16),
    _three(m.Pr, s16),
    _three(m.Pa, s16),
    _three(m.Vm, s16),
    st.builds(m.Ct, st.binary(min_size=7, max_size=7)),
    st.sampled_from(
        [m.Gs(), m.St(), m.Lp(), m.Zr(), m.GetSn(), m.GetRc(), m.GetRv(), m.GetRa(), m.GetBp()]
    ),
    st.builds(
        m.Tk,
        st.text(alphabet=st.characters(min_codepoint=1, max_codepoint=127), max_size=60),
    ),
    st.builds(m.Dp, s16, s16),
    st.builds(m.Da, s16, s16),
    st.builds(m.ConfSn, u8, st.lists(st.integers(0, 15), max_size=16).map(tuple)),
    st.builds(m.ConfTm, u8),
    st.builds(m.Ws, st.booleans(), st.booleans(), st.booleans(), u8),
    st.builds(m.ConfSer, u8, u16),
    st.builds(m.Mv, u16, s16, u16, s16, u16, s16),
)

flags16 = st.tuples(*[st.booleans()] * 16)

masks: st.SearchStrategy[StateMask] = st.builds(
    StateMask,
    ir=flags16,
    sonar=flags16,
    bumper=st.booleans(),
    pose=st.tuples(*[st.booleans()] * 4),
    velocity=st.tuples(*[st.booleans()] * 3),
    compass=st.booleans(),
)


@st.composite
def state_for_mask(draw: st.DrawFn, mask: StateMask) -> RobotState:
    """A state whose groups outside the mask are 0 (what decoding gives)."""

    def word(on: bool) -> int:
        return draw(s16) if on else 0

    return RobotState(
        sonar=tuple(draw(u8) if on else 0 for on in mask.sonar),
        bumper=draw(st.integers(0, 0xFF_FFFF)) if mask.bumper else 0,
        x=word(mask.pose[0]),
        y=word(mask.pose[1]),
        steer=word(mask.pose[2]),
        turret=word(mask.pose[3]),
        trans_vel=word(mask.velocity[0]),
        steer_vel=word(mask.velocity[1]),
        turret_vel=word(mask.velocity[2]),
        compass=word(mask.compass),
        motor_status=draw(u8),
        timestamp_ms=draw(st.integers(0, 0xFFFF_FFFF)),
        voltage_cpu_raw=draw(u8),
        voltage_motor_raw=draw(u8),
        ir=tuple(draw(st.integers(0, 15)) if on else 0 for on in mask.ir),
    )


packets: st.SearchStrategy[Packet] = st.builds(Packet, u8, st.binary(max_size=min(MAX_LEN - 2, 80)))
garbage_without_start = st.binary(max_size=40).map(lambda b: b.replace(b"\x01", b""))
