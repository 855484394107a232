"""`raycheck stress`: the extreme scenes in every variant (harness/commands/stress.py)."""
from __future__ import annotations

from .common import UsageError, out_folder, parser, run

PROG = "raycheck stress"


def main(argv: list[str]) -> int:
    ap = parser(PROG, "Render the extreme scenes of scenes/extreme in course mode, robust mode, "
                "course mode in float64 and Mitsuba, and measure each against the tracer's "
                "robust float64 render: NaN/inf pixels, the share of pixels more than one "
                "level off, SSIM and time; worst first, with images of the failures.",
                epilog="Exit status: 0 when robust mode passes every scene (no NaN/inf pixel, "
                       "SSIM >= 0.99), 1 when it fails one, 2 bad usage.")
    ap.add_argument("--out", type=out_folder, default=out_folder("out"), metavar="OUT",
                    help="the page goes to OUT/report/stress.html (default: out)")
    ap.add_argument("--scene", action="append", metavar="NAME",
                    help="only this extreme scene (by name, repeatable)")
    ap.add_argument("--no-mitsuba", action="store_true", help="leave Mitsuba out")
    ap.add_argument("--quiet", action="store_true", help="no table, only the page's path")
    args = ap.parse_args(argv)

    def stress() -> int:
        from ..catalog import bundled
        from ..commands.stress import format_table, run_stress
        from ..renderers import stress_variants

        scenes = bundled("extreme")
        if args.scene:
            names = {s.name for s in scenes}
            unknown = sorted(set(args.scene) - names)
            if unknown:
                raise UsageError(f"--scene: no extreme scene named {', '.join(unknown)} "
                                 f"(there are: {', '.join(sorted(names))})")
            scenes = [s for s in scenes if s.name in set(args.scene)]
        variants = stress_variants()
        if args.no_mitsuba:
            del variants["mitsuba"]
        rows = run_stress(scenes, args.out / "report", variants)
        if not args.quiet:
            print(format_table(rows))
        print(f"page: {(args.out / 'report' / 'stress.html').resolve()}")
        robust_fails = [r for r in rows if r.variant == "robust" and not r.passed]
        return 1 if robust_fails else 0

    return run(PROG, stress)
