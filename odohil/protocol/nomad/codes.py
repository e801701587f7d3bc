"""Command codes of the Nomad direct protocol (Ndirect.c ``#define``s)."""

from __future__ import annotations

from enum import IntEnum


class Code(IntEnum):
    """Packet TYPE byte: the request code, echoed as the reply type (CHOICE C2)."""

    AC = 1
    SP = 2
    PR = 3
    PA = 4
    VM = 5
    CT = 6
    GS = 7
    NAK = 8
    ST = 9
    LP = 10
    TK = 11
    DP = 12
    ZR = 13
    CONF_IR = 14
    CONF_SN = 15
    CONF_CP = 16
    CONF_LS = 17
    CONF_TM = 18
    GET_IR = 19
    GET_SN = 20
    GET_RC = 21
    GET_RV = 22
    GET_RA = 23
    GET_CP = 24
    GET_LS = 25
    SETUP_LS = 26
    GET_BP = 27
    CONF_SG = 28
    GET_SG = 29
    DA = 30
    WS = 31
    CONF_SER = 35
    MV = 43
    SPECIAL = 128


STATE_REPLY_CODES: frozenset[Code] = frozenset(
    {
        Code.AC,
        Code.SP,
        Code.PR,
        Code.PA,
        Code.VM,
        Code.MV,
        Code.CT,
        Code.GS,
        Code.ST,
        Code.LP,
        Code.DP,
        Code.DA,
        Code.WS,
        Code.ZR,
        Code.TK,
        Code.CONF_IR,
        Code.CONF_SN,
        Code.CONF_LS,
        Code.CONF_TM,
        Code.CONF_SG,
        Code.CONF_SER,
        Code.SETUP_LS,
    }
)
"""Requests the robot answers with a full state packet (Ndirect ``Process_Robot_Resp``)."""

MOTION_CODES: frozenset[Code] = frozenset({Code.PR, Code.PA, Code.VM, Code.MV, Code.ZR})
"""Requests that start a motion: never resent automatically (CHOICE C11)."""
