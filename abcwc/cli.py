"""The ``abcwc`` command: ``demo``, ``bench``, ``course`` and ``posegraph``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def _demo(args: argparse.Namespace) -> int:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from abcwc import viz
    from abcwc.navigation import SonarAvoider
    from abcwc.sim import SimBase

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    chair = SimBase(world=args.world, seed=args.seed)
    log = chair.run(SonarAvoider(), args.seconds, progress=not args.quiet)
    figure = viz.plot_run(log, chair.world)
    plot_path = out / "demo_wander.png"
    figure.savefig(plot_path, dpi=110, bbox_inches="tight")
    plt.close(figure)
    animation = viz.animate_run(log, chair.world)
    animation_path = viz.save_animation(animation, out / "demo_wander.gif")
    log_path = log.save(out / "demo_wander.npz")
    print(f"sonar-avoidance wander in {chair.world.name} (seed {args.seed}): {log.summary()}; "
          f"wrote {plot_path}, {animation_path}, {log_path}")
    return 0


def _bench(args: argparse.Namespace) -> int:
    from abcwc.bench import format_table, run_benchmarks, to_json

    results = run_benchmarks(args.names or None, repeats=args.repeats)
    print(to_json(results) if args.json else format_table(results))
    return 0


def _posegraph(args: argparse.Namespace) -> int:
    """Optimise a g2o pose graph; one ``abcwc: error:`` line and status 2 on bad input."""
    from abcwc.mapping.g2o import read_g2o, write_g2o
    from abcwc.mapping.posegraph import optimise

    try:
        graph = read_g2o(args.file)
        poses, result = optimise(graph, robust=args.robust, initial=args.initial,
                                 max_iterations=args.max_iterations,
                                 progress=args.progress)
        if args.out:
            write_g2o(graph.with_poses(poses), args.out)
    except (ValueError, OSError) as exc:
        print(f"abcwc: error: {exc}", file=sys.stderr)
        return 2
    print(f"chi2 initial {result.chi2_initial:.6g} final {result.chi2_final:.6g}, "
          f"{result.iterations} iterations, {result.seconds:.3f} s ({result.reason})")
    if args.out:
        print(f"wrote {args.out}")
    return 0


def _course(rest: list[str]) -> int:
    from abcwc import course

    if not rest or rest[0] != "build":
        print("usage: abcwc course build [--check] [--solutions DIR] [--course DIR]",
              file=sys.stderr)
        return 2
    return course.main(rest[1:])


def build_parser() -> argparse.ArgumentParser:
    """The command-line parser."""
    parser = argparse.ArgumentParser(prog="abcwc", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    demo = commands.add_parser("demo", help="run the headless course demo")
    demo.add_argument("--out", default="abcwc-demo", help="folder for the plot, animation, log")
    demo.add_argument("--world", default="lab")
    demo.add_argument("--seed", type=int, default=0)
    demo.add_argument("--seconds", type=float, default=300.0, help="simulated seconds")
    demo.add_argument("--quiet", action="store_true", help="no progress bar")
    bench = commands.add_parser("bench", help="run the benchmarks")
    bench.add_argument("names", nargs="*", help="benchmarks to run (default: all)")
    bench.add_argument("--json", action="store_true", help="print JSON instead of a table")
    bench.add_argument("--repeats", type=int, default=3)
    posegraph = commands.add_parser("posegraph", help="optimise a g2o pose graph (sparse LM)")
    posegraph.add_argument("file", help="EDGE_SE2/VERTEX_SE2 graph, .g2o or .g2o.gz")
    posegraph.add_argument("--out", help="write the optimised graph here (.g2o or .g2o.gz)")
    posegraph.add_argument("--robust", choices=["huber", "cauchy"], help="robust kernel")
    posegraph.add_argument("--initial", choices=["lago", "given"], default="lago",
                           help="start from LAGO's estimate (default) or the file's poses")
    posegraph.add_argument("--max-iterations", type=int, default=100)
    posegraph.add_argument("--progress", action="store_true", help="show a progress bar")
    commands.add_parser("course", help="build the student notebooks: course build [--check]",
                        add_help=False)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``abcwc`` console script."""
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    if argv and argv[0] == "course":
        return _course(argv[1:])
    args = parser.parse_args(argv)
    try:
        return {"demo": _demo, "bench": _bench, "posegraph": _posegraph}[args.command](args)
    except ValueError as exc:
        parser.exit(2, f"abcwc {args.command}: {exc}\n")
    return 1


if __name__ == "__main__":
    sys.exit(main())
