"""The iRobot Create 2 Open Interface (OI), bytes in and typed values out.

No I/O here: ``numbers`` (two's complement, high byte first; encoder wrap),
``opcodes`` (command opcodes, modes and how many data bytes each command
takes), ``commands`` (host commands and a splitter of a command byte stream),
``packets`` (sensor packets and groups), ``stream`` (the stream frame and its
resynchronising decoder). Values are in OI units: mm, mm/s, degrees, counts.
The protocol as odohil implements it, with its CHOICEs, is described in
protocols/create2/README.md.
"""
