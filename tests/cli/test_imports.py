"""``odohil --help`` (and a command's help) loads no fake robot: the fakes'
URL handlers are registered only by the commands that open a fake's port."""

from __future__ import annotations

import subprocess
import sys

import pytest

_PROBE = """
import sys
from odohil.cli.app import main
sys.argv = ["odohil", *sys.argv[1:]]
try:
    main()
except SystemExit:
    pass
loaded = sorted(m for m in sys.modules if m == "fakes" or m.startswith("fakes."))
print("FAKES:", ",".join(loaded))
"""


@pytest.mark.parametrize("args", [["--help"], ["run", "--help"], ["emulate", "--help"]])
def test_help_imports_no_fake(args: list[str]) -> None:
    done = subprocess.run(
        [sys.executable, "-c", _PROBE, *args], capture_output=True, text=True, timeout=60
    )
    assert "Usage" in done.stdout
    assert done.stdout.strip().splitlines()[-1] == "FAKES:"


def test_a_fake_port_registers_the_handler_when_asked() -> None:
    probe = (
        "import serial\n"
        "from odohil.cli.session_view import register_fake_urls\n"
        "register_fake_urls('/dev/ttyUSB0')\n"
        "assert 'fakes' not in serial.protocol_handler_packages\n"
        "register_fake_urls('fakerobot://?seed=1')\n"
        "port = serial.serial_for_url('fakerobot://?seed=1', timeout=0.1)\n"
        "port.close()\n"
        "print('ok')\n"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=60)
    assert done.stdout.strip() == "ok", done.stderr
