"""The ``abcwc`` command: ``demo``, ``bench``, ``posegraph``, ``slam`` and ``course build``.

A mistake in what the user gave (an unknown world or benchmark, a bad number, a missing
data folder, ``course build`` outside a checkout, ...) ends the command with one line
``abcwc: error: <message>`` on stderr and exit status 2; argparse reports what it
finds itself (an unknown option, a value of the wrong type) its own way, also with 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

PROG = "abcwc"
USAGE_ERROR = 2

USER_ERRORS: tuple[type[Exception], ...] = (ValueError, OSError)
"""What the library raises for bad input: ValueError for a bad value (an unknown world or
benchmark, a negative seed or duration), OSError for a file or folder (a missing data
folder or world file, an output folder that cannot be written, no checkout)."""


def _demo(args: argparse.Namespace) -> int:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from abcwc import viz
    from abcwc.navigation import SonarAvoider
    from abcwc.sim import SimBase

    out = Path(args.out)
    chair = SimBase(world=args.world, seed=args.seed)
    out.mkdir(parents=True, exist_ok=True)
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
    """Optimise a g2o pose graph and print chi2 before and after, iterations and time."""
    from abcwc.mapping.g2o import read_g2o, write_g2o
    from abcwc.mapping.posegraph import optimise

    graph = read_g2o(args.file)
    poses, result = optimise(graph, robust=args.robust, initial=args.initial,
                             max_iterations=args.max_iterations, progress=args.progress)
    if args.out:
        write_g2o(graph.with_poses(poses), args.out)
    print(f"chi2 initial {result.chi2_initial:.6g} final {result.chi2_final:.6g}, "
          f"{result.iterations} iterations, {result.seconds:.3f} s ({result.reason})")
    if args.out:
        print(f"wrote {args.out}")
    return 0


def _slam(args: argparse.Namespace) -> int:
    """Graph SLAM on a CARMEN log: map and trajectory to a folder, relation errors."""
    import numpy as np

    from abcwc.mapping.carmen import read_carmen_log
    from abcwc.mapping.map_io import save_map
    from abcwc.mapping.relations import format_relation_errors, read_relations, relation_errors
    from abcwc.mapping.slam import render, run_slam

    log = read_carmen_log(args.log, max_range=args.max_range,
                          laser_offset=None if args.laser_offset is None
                          else tuple(args.laser_offset))
    relations = read_relations(args.relations, log.stamps) if args.relations else None
    result = run_slam(log, progress=not args.quiet)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    save_map(render(log, result.scan_poses, result.keyframes), out / "map.yaml")
    trajectory = np.column_stack([log.stamps, result.scan_poses])
    np.savetxt(out / "trajectory.txt", trajectory, fmt="%.6f",
               header="stamp (s) x (m) y (m) theta (rad): one line per scan")
    duration = float(log.stamps[-1] - log.stamps[0])
    print(f"{len(log)} scans, {len(result.keyframes)} keyframes, {result.loops} loop closures "
          f"in {result.seconds:.1f} s ({duration / result.seconds:.0f}x faster than recorded)")
    if relations is not None:
        print(format_relation_errors(relation_errors(result.laser_poses, relations)))
    print(f"wrote {out / 'map.yaml'}, {out / 'map.pgm'} and {out / 'trajectory.txt'}")
    return 0


def _navtrial(args: argparse.Namespace) -> int:
    """The navigator's random-goal trial in a world with its people walking."""
    from abcwc.experiments.navigation_trial import run_trial

    if args.goals < 1:
        raise ValueError(f"--goals must be at least 1, got {args.goals}")
    result = run_trial(goals=args.goals, seed=args.seed, world=args.world,
                       people=not args.no_people, progress=not args.quiet)
    print(result.summary())
    return 0


def _course_build(args: argparse.Namespace) -> int:
    from abcwc import course

    return course.run(args.solutions, args.course, check=args.check)


def build_parser() -> argparse.ArgumentParser:
    """The command-line parser."""
    parser = argparse.ArgumentParser(prog=PROG, description=__doc__.splitlines()[0])
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    demo = commands.add_parser("demo", help="run the headless course demo")
    demo.add_argument("--out", default="abcwc-demo", help="folder for the plot, animation, log")
    demo.add_argument("--world", default="lab", help="a world's name or a .json world file")
    demo.add_argument("--seed", type=int, default=0)
    demo.add_argument("--seconds", type=float, default=300.0, help="simulated seconds")
    demo.add_argument("--quiet", action="store_true", help="no progress bar")
    demo.set_defaults(run=_demo)

    bench = commands.add_parser("bench", help="run the benchmarks")
    bench.add_argument("names", nargs="*", help="benchmarks to run (default: all)")
    bench.add_argument("--json", action="store_true", help="print JSON instead of a table")
    bench.add_argument("--repeats", type=int, default=3)
    bench.set_defaults(run=_bench)

    course = commands.add_parser("course", help="build the student notebooks: course build")
    actions = course.add_subparsers(dest="action", required=True, metavar="ACTION")
    build = actions.add_parser(
        "build", help="regenerate course/ from solutions/ (in a checkout of the repository)",
        description="Build the student notebooks in course/ from the solutions.")
    build.add_argument("--check", action="store_true",
                       help="write nothing; exit 1 if course/ is not what a build would write")
    build.add_argument("--solutions", metavar="DIR",
                       help="solution notebooks (default: solutions, in a checkout's root)")
    build.add_argument("--course", metavar="DIR",
                       help="student notebooks to write (default: course)")
    build.set_defaults(run=_course_build)

    posegraph = commands.add_parser("posegraph", help="optimise a g2o pose graph (sparse LM)")
    posegraph.add_argument("file", help="g2o graph (.g2o or .g2o.gz), e.g. data/slam/MIT.g2o.gz")
    posegraph.add_argument("--out", help="write the optimised graph here (.g2o or .g2o.gz)")
    posegraph.add_argument("--robust", choices=["huber", "cauchy"], help="robust kernel")
    posegraph.add_argument("--initial", choices=["lago", "given"], default="lago",
                           help="start from LAGO's estimate (default) or the file's poses")
    posegraph.add_argument("--max-iterations", type=int, default=100)
    posegraph.add_argument("--progress", action="store_true", help="show a progress bar")
    posegraph.set_defaults(run=_posegraph)

    slam = commands.add_parser("slam", help="graph SLAM on a CARMEN laser log")
    slam.add_argument("log", help="CARMEN log (.clf or .clf.gz), e.g. data/slam/aces.clf.gz")
    slam.add_argument("--relations", help="benchmark relations file: print the errors")
    slam.add_argument("--out", default="abcwc-slam", help="folder for map and trajectory")
    slam.add_argument("--max-range", type=float, help="the laser's maximum range (m)")
    slam.add_argument("--laser-offset", type=float, nargs=3, metavar=("X", "Y", "THETA"),
                      help="the laser's pose on the robot (m, m, rad)")
    slam.add_argument("--quiet", action="store_true", help="no progress bar")
    slam.set_defaults(run=_slam)

    navtrial = commands.add_parser(
        "navtrial", help="drive the navigator to seeded random goals, judged by ground truth")
    navtrial.add_argument("--goals", type=int, default=50)
    navtrial.add_argument("--seed", type=int, default=0)
    navtrial.add_argument("--world", default="floor", help="a world's name or a .json file")
    navtrial.add_argument("--no-people", action="store_true", help="without walking people")
    navtrial.add_argument("--quiet", action="store_true", help="no progress bar")
    navtrial.set_defaults(run=_navtrial)
    return parser


def error_line(exc: BaseException) -> str:
    """``abcwc: error: <message>`` for a user error, on one line."""
    if isinstance(exc, OSError) and exc.strerror and exc.filename is not None:
        message = f"{exc.filename}: {exc.strerror}"  # not "[Errno 21] Is a directory: ..."
    else:
        message = str(exc) or type(exc).__name__
    lines = (line.strip() for line in message.splitlines())
    return f"{PROG}: error: {' '.join(line for line in lines if line)}"


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``abcwc`` console script; returns the exit status."""
    args = build_parser().parse_args(sys.argv[1:] if argv is None else argv)
    try:
        return args.run(args)
    except USER_ERRORS as exc:
        print(error_line(exc), file=sys.stderr)
        return USAGE_ERROR


if __name__ == "__main__":
    sys.exit(main())
