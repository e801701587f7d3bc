"""Time pose_moments and the forth-and-back closed forms.

Run: python bench/pose_moments.py
"""

from __future__ import annotations

import timeit

from odohil.science.closed_forms import forth_and_back_means
from odohil.science.moments import pose_moments
from odohil.science.parameters import NOMAD150, ErrorParameters
from odohil.science.paths import Design, polygonal_circle

EXAGGERATED = ErrorParameters.from_paper_units(20.0, -0.05, 200.0, 1e-3)


def best_us(call: object, repeat: int = 7, number: int = 200) -> float:
    times = timeit.repeat(call, repeat=repeat, number=number)  # type: ignore[arg-type]
    return min(times) / number * 1e6


def main() -> None:
    cases = [
        ("k=20 l=0.5 m turn (40 legs)", Design(20, 0.5).path()),
        ("k=20 l=0.5 m reverse (40 legs)", Design(20, 0.5, "reverse").path()),
        ("polygonal circle r=2 m, 40 sides", polygonal_circle(2.0, 40)),
        ("k=1 l=6 m turn (2 legs)", Design(1, 6.0).path()),
    ]
    for label, path in cases:
        for name, params in (("Nomad 150", NOMAD150), ("exaggerated", EXAGGERATED)):
            us = best_us(lambda p=path, q=params: pose_moments(p, q))
            print(f"pose_moments  {label:34s} {name:12s} {us:8.1f} us/call")
    design = Design(20, 0.5)
    us = best_us(lambda: forth_and_back_means(design, NOMAD150), number=2000)
    print(f"forth_and_back_means k=20 l=0.5 m turn {'':27s} {us:8.1f} us/call")


if __name__ == "__main__":
    main()
