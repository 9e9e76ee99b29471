"""``rotorid generate``: fly a flight condition's data set with the truth model."""

from __future__ import annotations

import sys
import time

from rotorid.cli.arguments import output_directory, seed


def add_arguments(parser) -> None:
    parser.add_argument("condition", choices=("hover", "forward"),
                        help="hover, or forward flight at 70 kt")
    parser.add_argument("--out", required=True, metavar="DIR", type=output_directory,
                        help="directory for the maneuver files and manifest.json")
    parser.add_argument("--seed", type=seed, default=0,
                        help="seed of the sensor noise and gusts (0)")
    parser.add_argument("--turbulence", default="still",
                        choices=("still", "light", "moderate"),
                        help="Dryden turbulence, MIL-F-8785C presets at 100 ft "
                             "(docs/truth-model.md); default still air")
    parser.add_argument("--rotor-channels", action="store_true",
                        help="also write the coning and tip-path-plane tilts beta0 beta1c "
                             "beta1s (deg, with sensor noise; docs/hybrid.md)")
    parser.add_argument("--quick", action="store_true",
                        help="shorter records (duration scale 0.3), for trying things out")


class _Progress:
    """Prints the flight's progress on stderr, in place on a terminal."""

    def __init__(self, label: str):
        self.label, self.start, self.shown = label, time.monotonic(), -1
        self.inline = sys.stderr.isatty()

    def __call__(self, fraction: float) -> None:
        percent = int(100 * fraction)
        step = 1 if self.inline else 25
        if percent // step == self.shown // step and percent < 100:
            return
        self.shown = percent
        text = f"{self.label}: {percent:3d} % ({time.monotonic() - self.start:.0f} s)"
        end = "\n" if (percent >= 100 or not self.inline) else ""
        print(("\r" if self.inline else "") + text, end=end, file=sys.stderr, flush=True)


def run(args) -> int:
    from ..source import HelisimSource

    settings = {"condition": args.condition, "seed": args.seed, "turbulence": args.turbulence}
    if args.quick:
        settings["quick"] = True
    if args.rotor_channels:
        settings["rotor_channels"] = True
    source = HelisimSource(progress=_Progress(f"flying the {args.condition} maneuvers"))
    maneuvers, cached = source.generate_into(settings, args.out)
    state = "unchanged, read from the cache" if cached else "written"
    print(f"{args.condition}: {len(maneuvers)} maneuvers {state} in {args.out}")
    return 0
