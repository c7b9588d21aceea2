"""How many of each lab's catalogued mistakes its visible checks fail, and for how many of those the message says
what to fix (issue 34). Runs the checks in this process (autograder/authoring/visible_checks.py); no timing.

    PYTHONPATH=. .venv/bin/python benchmarks/visible_messages.py
"""

from __future__ import annotations

from autograder.authoring.visible_checks import mistakes_caught
from autograder.labs import all_labs


def main() -> None:
    print(f"{'lab':<20}{'mistakes':>9}{'fail a check':>14}{'names the fix':>15}")
    totals = [0, 0, 0]
    for lab in all_labs():
        caught, named, count = mistakes_caught(lab)
        totals = [totals[0] + count, totals[1] + caught, totals[2] + named]
        print(f"{lab.id:<20}{count:>9}{caught:>14}{named:>15}")
    print(f"{'all':<20}{totals[0]:>9}{totals[1]:>14}{totals[2]:>15}  "
          f"({totals[2] / max(totals[1], 1):.0%} of those that fail a check name the fix)")


if __name__ == "__main__":
    main()
