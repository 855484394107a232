"""`raycheck gallery`: the bundled course scenes rendered by the tracer."""
from __future__ import annotations

from .common import out_folder, parser, positive_int, run

PROG = "raycheck gallery"


def main(argv: list[str]) -> int:
    ap = parser(PROG, "Render the bundled course scenes with the tracer into OUT/gallery "
                "(color, normals and depth images).")
    ap.add_argument("--out", type=out_folder, default=out_folder("out"), metavar="OUT",
                    help="the images go to OUT/gallery (default: out)")
    ap.add_argument("--size", type=positive_int, nargs=2, metavar=("W", "H"),
                    help="image size (default: a scene's own, else 800 800)")
    ap.add_argument("--quiet", action="store_true", help="print only where the images are")
    args = ap.parse_args(argv)

    def gallery() -> int:
        from ..commands.gallery import render_gallery

        out = args.out / "gallery"
        if out.exists() and not out.is_dir():
            raise OSError(20, "not a folder", str(out))
        for name, seconds, path in render_gallery(out, tuple(args.size) if args.size else None):
            if not args.quiet:
                print(f"{name:<20} {seconds:6.2f} s  {path}")
        print(f"images in {out.resolve()}")
        return 0

    return run(PROG, gallery)
