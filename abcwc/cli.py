"""The abcwc command: demo, bench, posegraph, slam, navtrial, followtrial, errands,
hubtrial, dashboard and course build.

Every command takes the same few options:

- ``--quiet``: no progress bars (they are on by default and go to stderr);
- ``--json``: the figures as one JSON object on stdout instead of text (every command
  that prints figures: demo, bench, posegraph, slam, navtrial, followtrial, errands,
  hubtrial);
- ``--out DIR``: a folder, created when the command writes into it (demo, posegraph, slam);
- ``--debug``: an error shows its traceback.

A mistake in what the user gave (an unknown world or benchmark, a bad number, a missing
file or data folder, ``course build`` outside a checkout, ...) ends the command with one
line ``abcwc: error: <message>`` on stderr and exit status 2; argparse reports what it
finds itself (an unknown option, a value of the wrong type) its own way, also with 2. Any
other exception is a bug in abcwc: one line says so (exit status 1, as Python's own for an
uncaught exception), and ``--debug`` shows its traceback. ``abcwc demo`` exits with 3 when
its errand did not arrive. Options are checked before any
folder is made, so a refused command leaves nothing behind.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import subprocess
import sys
from pathlib import Path

PROG = "abcwc"
USAGE_ERROR = 2
INTERNAL_ERROR = 1
MISSION_FAILED = 3
"""``abcwc demo``'s exit status when the errand did not arrive (the report says why)."""

USER_ERRORS: tuple[type[Exception], ...] = (
    ValueError, FileNotFoundError, IsADirectoryError, NotADirectoryError, PermissionError,
    FileExistsError)
"""What the library raises for bad input: ValueError for a bad value (an unknown world or
benchmark, a negative seed or duration, a file that is not what it should be; abcwc's own
input errors, such as GraphFileError or WorldError, are ValueErrors), and the OSErrors of
a path the user named (missing, a folder where a file belongs or the other way round, not
readable or writable; NotACheckoutError is a FileNotFoundError)."""


def _version() -> str:
    from abcwc import __version__

    return __version__


def _print_json(figures: dict) -> None:
    """``figures`` as JSON on stdout: NumPy numbers as plain ones, NaN and infinity as
    null (JSON has neither)."""

    def plain(value: object) -> object:
        if isinstance(value, dict):
            return {str(k): plain(v) for k, v in value.items()}
        if isinstance(value, (list, tuple)):
            return [plain(v) for v in value]
        if hasattr(value, "item"):  # a NumPy scalar
            value = value.item()  # type: ignore[union-attr]
        if isinstance(value, float) and not math.isfinite(value):
            return None
        return value

    print(json.dumps(plain(figures), indent=2, sort_keys=True))


def _out_folder(path: str) -> Path:
    """``--out`` as a folder to write into, checked now and made later (only when the
    command has something to write): an existing file there is refused."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise NotADirectoryError(f"--out {out}: a file is there; --out names a folder")
    return out


def _demo(args: argparse.Namespace) -> int:
    """The named mission: the capstone's errand (the default) or chapter 03's wander."""
    if args.mission == "wander":
        return _demo_wander(args)
    return _demo_errand(args)


def _demo_errand(args: argparse.Namespace) -> int:
    """The ABC concept end to end (:mod:`abcwc.experiments.errand`): map the floor, be
    told where to go, go there among people; the report in ``--out``."""
    if args.seconds is not None:
        raise ValueError("--seconds is the wander's; the errand ends when it arrives or "
                         "fails (use --mission wander --seconds S)")
    out = _out_folder(args.out)
    from abcwc.experiments.errand import capstone_errand, errand_destination
    from abcwc.sim.world import load_world

    world = load_world(args.world or "floor")
    destination = errand_destination(world, args.to)
    result, grid, files = capstone_errand(world, destination, seed=args.seed, out=out,
                                          spoken=not args.typed, progress=not args.quiet)
    import matplotlib

    matplotlib.use("Agg")
    from abcwc.viz.report import write_errand_report

    report = write_errand_report(result, grid, out, world)
    files = [str(report), *files, str(out / "errand.gif")]
    if args.json:
        _print_json({**result.figures(), "seed": args.seed, "files": files})
    else:
        print(f"{result.summary()}; wrote {', '.join(files)}")
    return 0 if result.arrived else MISSION_FAILED


def _demo_wander(args: argparse.Namespace) -> int:
    seconds = 300.0 if args.seconds is None else args.seconds
    if not (math.isfinite(seconds) and seconds > 0):
        raise ValueError(f"--seconds must be a finite number > 0, got {seconds:g}")
    if args.to is not None:
        raise ValueError("--to is the errand's; the wander goes nowhere in particular")
    out = _out_folder(args.out)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from abcwc import viz
    from abcwc.behaviours import SonarAvoider
    from abcwc.sim import SimBase

    chair = SimBase(world=args.world or "lab", seed=args.seed)
    out.mkdir(parents=True, exist_ok=True)
    log = chair.run(SonarAvoider(), seconds, progress=not args.quiet)
    figure = viz.plot_run(log, chair.world)
    plot_path = out / "demo_wander.png"
    figure.savefig(plot_path, dpi=110, bbox_inches="tight")
    plt.close(figure)
    animation = viz.animate_run(log, chair.world)
    animation_path = viz.save_animation(animation, out / "demo_wander.gif")
    log_path = log.save(out / "demo_wander.npz")
    files = [str(plot_path), str(animation_path), str(log_path)]
    if args.json:
        _print_json({"mission": "wander", "world": chair.world.name, "seed": args.seed,
                     "seconds": float(log.t[-1] - log.t[0] + log.period),
                     "distance_m": log.distance_travelled() if log.has_ground_truth
                     else None,
                     "collisions": int(log.collisions[-1]), "files": files})
        return 0
    print(f"sonar-avoidance wander in {chair.world.name} (seed {args.seed}): {log.summary()}; "
          f"wrote {', '.join(files)}")
    return 0


def _bench(args: argparse.Namespace) -> int:
    from abcwc.bench import format_table, run_benchmarks, to_json

    results = run_benchmarks(args.names or None, repeats=args.repeats,
                             progress=not args.quiet)
    print(to_json(results) if args.json else format_table(results))
    return 0


POSEGRAPH_FILE = "optimised.g2o"
"""What ``posegraph --out DIR`` writes in DIR: the graph with its optimised poses."""


def _posegraph(args: argparse.Namespace) -> int:
    """Optimise a g2o pose graph and print chi2 before and after, iterations and time."""
    from abcwc.mapping.g2o import read_g2o, write_g2o
    from abcwc.mapping.posegraph import optimise

    out = _out_folder(args.out) if args.out else None
    graph = read_g2o(args.file)
    poses, result = optimise(graph, robust=args.robust, initial=args.initial,
                             max_iterations=args.max_iterations, progress=not args.quiet)
    files = []
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        files.append(str(write_g2o(graph.with_poses(poses), out / POSEGRAPH_FILE)))
    if args.json:
        _print_json({"file": args.file, "poses": len(graph.poses),
                     "edges": len(graph.edges), "chi2_initial": result.chi2_initial,
                     "chi2_final": result.chi2_final, "iterations": result.iterations,
                     "seconds": result.seconds, "converged": result.converged,
                     "reason": result.reason, "files": files})
        return 0
    print(f"chi2 initial {result.chi2_initial:.6g} final {result.chi2_final:.6g}, "
          f"{result.iterations} iterations, {result.seconds:.3f} s ({result.reason})")
    if files:
        print(f"wrote {files[0]}")
    return 0


def _slam(args: argparse.Namespace) -> int:
    """Graph SLAM on a CARMEN log: map and trajectory to a folder, relation errors."""
    out = _out_folder(args.out)

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
    out.mkdir(parents=True, exist_ok=True)
    save_map(render(log, result.scan_poses, result.keyframes), out / "map.yaml")
    trajectory = np.column_stack([log.stamps, result.scan_poses])
    np.savetxt(out / "trajectory.txt", trajectory, fmt="%.6f",
               header="stamp (s) x (m) y (m) theta (rad): one line per scan")
    files = [str(out / name) for name in ("map.yaml", "map.pgm", "trajectory.txt")]
    duration = float(log.stamps[-1] - log.stamps[0])
    errors = relation_errors(result.laser_poses, relations) if relations is not None else None
    if args.json:
        _print_json({
            "log": args.log, "scans": len(log), "keyframes": len(result.keyframes),
            "loop_closures": result.loops, "seconds": result.seconds,
            "times_faster_than_recorded": duration / result.seconds,
            "relation_errors": None if errors is None else {
                "relations": len(errors.translational),
                "translational_mean_m": errors.translational_mean,
                "translational_std_m": errors.translational_std,
                "rotational_mean_deg": errors.rotational_mean_deg,
                "rotational_std_deg": errors.rotational_std_deg},
            "files": files})
        return 0
    print(f"{len(log)} scans, {len(result.keyframes)} keyframes, {result.loops} loop closures "
          f"in {result.seconds:.1f} s ({duration / result.seconds:.0f}x faster than recorded)")
    if errors is not None:
        print(format_relation_errors(errors))
    print(f"wrote {files[0]}, {files[1]} and {files[2]}")
    return 0


NAVTRIAL_GOAL_FIGURES = ("status", "reason", "reached", "seconds", "driven", "straight",
                         "planned", "final_error", "final_heading_error", "collisions",
                         "lethal_periods", "closest_person", "max_localisation_error", "phases",
                         "recoveries")
"""Each goal's figures in ``navtrial --json`` (m, s, rad; GoalOutcome's names)."""


def _navtrial(args: argparse.Namespace) -> int:
    """The navigator's random-goal trial in a world with its people walking."""
    from abcwc.experiments.navigation_trial import run_trial

    if args.goals < 1:
        raise ValueError(f"--goals must be at least 1, got {args.goals}")
    result = run_trial(goals=args.goals, seed=args.seed, world=args.world,
                       people=not args.no_people, progress=not args.quiet)
    if args.json:
        _print_json({
            "world": args.world, "seed": args.seed, "people": not args.no_people,
            "goals": len(result.outcomes), "success_rate": result.success_rate,
            "collisions": result.collisions, "lethal_periods": result.lethal_periods,
            "closest_person": result.closest_person,
            "outcomes": [{"goal": [o.goal.x, o.goal.y, o.goal.theta],
                          **{name: getattr(o, name) for name in NAVTRIAL_GOAL_FIGURES}}
                         for o in result.outcomes]})
        return 0
    print(result.summary())
    return 0


def _followtrial(args: argparse.Namespace) -> int:
    """The tag follower's trials (lab, building), seeds 0..n-1, with A.13's follower on
    the same walks."""
    from abcwc.experiments.follow_trial import TRIAL_WORLDS, run_trial_in, trials_table

    if args.seeds < 1:
        raise ValueError(f"--seeds must be at least 1, got {args.seeds}")
    worlds = TRIAL_WORLDS if args.world == "all" else (args.world,)
    results = {}
    for where in worlds:
        for seed in range(args.seeds):
            for who, thesis in (("tag", False), ("A.13", True)):
                results[(where, who, seed)] = run_trial_in(where, seed, thesis)
    if args.json:
        _print_json({"runs": [{"world": where, "follower": who, "seed": seed,
                               **result.figures()}
                              for (where, who, seed), result in results.items()]})
    else:
        print(trials_table(results))
    return 0


def _errands(args: argparse.Namespace) -> int:
    """The capstone's trial: errands to seeded random places from the chair's own map."""
    from abcwc.experiments.errand import errands_table, run_errands

    if args.count < 1:
        raise ValueError(f"--count must be at least 1, got {args.count}")
    results = run_errands(args.count, seed=args.seed, world=args.world,
                          progress=not args.quiet)
    if args.json:
        _print_json({"world": args.world, "seed": args.seed, "count": len(results),
                     "arrived": sum(r.arrived for r in results),
                     "errands": [r.figures() for r in results]})
    else:
        print(errands_table(results))
    return 0


def _hubtrial(args: argparse.Namespace) -> int:
    """Classes of N students at once on a JupyterHub on this machine, each running a
    chapter on a server of their own: time per chapter and memory per server."""
    import tempfile

    from abcwc.hub import LocalHub, class_figures, class_table, doubling_point, run_class

    try:
        sizes = sorted({int(part) for part in args.students.split(",")})
    except ValueError:
        raise ValueError(f"--students takes class sizes separated by commas (1,2,4,8), "
                         f"got {args.students!r}") from None
    if not sizes or sizes[0] < 1:
        raise ValueError(f"--students: every class size must be 1 or more, got {args.students}")
    try:
        import jupyterhub  # noqa: F401
    except ImportError:
        raise FileNotFoundError("abcwc hubtrial needs jupyterhub: pip install -e '.[test]'") \
            from None
    classes = {}
    with tempfile.TemporaryDirectory(prefix="abcwc-hub-") as folder:
        hub = LocalHub(folder)
        hub.check_chapter(args.chapter)
        with hub:
            for size in sizes:
                classes[size] = run_class(hub, size, args.chapter,
                                          prefix=f"n{size}-student")
                if not args.quiet:
                    print(f"{size} students: done", file=sys.stderr)
    if args.json:
        _print_json({"chapter": args.chapter, "classes": class_figures(classes),
                     "doubling_students": doubling_point(classes)})
    else:
        print(class_table(classes, args.chapter))
    return 0


def _dashboard(args: argparse.Namespace) -> int:
    """Serve the rider's dashboard on the simulated chair as a page of its own (Voila),
    in the foreground until Ctrl-C."""
    from abcwc.sim.world import load_world
    from abcwc.ui.dashboard import VOILA_IP, WORLD_VARIABLE, voila_command

    command = voila_command(args.port, open_browser=not args.no_browser)
    world = load_world(args.world)  # an unknown world is refused before any server starts
    given = Path(args.world)
    # a world file by its full path: the page's kernel runs in the notebook's folder
    named = str(given.resolve()) if given.suffix == ".json" or given.exists() else args.world
    print(f"the rider's dashboard on the {world.name} world: http://{VOILA_IP}:{args.port}/ "
          f"(Ctrl-C stops it)", flush=True)
    return _serve(command, {**os.environ, WORLD_VARIABLE: named})


def _serve(command: list[str], env: dict[str, str]) -> int:
    """Run a server in the foreground until it ends; on Ctrl-C ask it to stop (SIGTERM:
    a Jupyter server then shuts its kernels down) and wait 10 s for it; its exit
    status."""
    with subprocess.Popen(command, env=env) as server:
        try:
            return server.wait()
        except KeyboardInterrupt:
            server.terminate()
            try:
                server.wait(timeout=10)
            except subprocess.TimeoutExpired:
                server.kill()
            return 0


def _course_build(args: argparse.Namespace) -> int:
    from abcwc import course

    if not args.quiet:
        return course.run(args.solutions, args.course, check=args.check)
    with contextlib.redirect_stdout(io.StringIO()):  # the exit status still tells
        return course.run(args.solutions, args.course, check=args.check)


def _common_options(for_every_command: bool) -> argparse.ArgumentParser:
    """``--quiet`` and ``--debug``, given before the command or after it. A command's
    copy has no default of its own (SUPPRESS), so it does not undo the one before it."""
    common = argparse.ArgumentParser(add_help=False)
    default = argparse.SUPPRESS if for_every_command else False
    common.add_argument("--quiet", action="store_true", default=default,
                        help="no progress bars (course build: print nothing but errors)")
    common.add_argument("--debug", action="store_true", default=default,
                        help="show the traceback of an error")
    return common


def _json_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--json", action="store_true",
                        help="print the figures as JSON instead of text")


def build_parser() -> argparse.ArgumentParser:
    """The command-line parser."""
    parser = argparse.ArgumentParser(prog=PROG, description=__doc__.splitlines()[0],
                                     parents=[_common_options(False)])
    parser.add_argument("--version", action="version", version=f"{PROG} {_version()}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    common = [_common_options(True)]

    demo = commands.add_parser(
        "demo", parents=common,
        help="run the headless course demo: the chair maps the floor, is told where to go "
             "and goes there among people (or --mission wander)")
    demo.add_argument("--mission", choices=["errand", "wander"], default="errand",
                      help="errand (default): map, be told, go; wander: chapter 03's "
                           "sonar-avoidance wander")
    demo.add_argument("--out", default="abcwc-demo", metavar="DIR",
                      help="folder for the report, map, animation and log (default: "
                           "abcwc-demo)")
    demo.add_argument("--world", default=None,
                      help="a world's name or a .json world file (default: floor for the "
                           "errand, lab for the wander)")
    demo.add_argument("--to", metavar="PLACE",
                      help="the errand's destination: a place of the world (default: the "
                           "cafeteria)")
    demo.add_argument("--seed", type=int, default=0)
    demo.add_argument("--typed", action="store_true",
                      help="type the command instead of speaking it (flite and the "
                           "recogniser)")
    demo.add_argument("--seconds", type=float, default=None,
                      help="the wander's simulated seconds (default 300)")
    _json_option(demo)
    demo.set_defaults(run=_demo)

    bench = commands.add_parser("bench", help="run the benchmarks", parents=common)
    bench.add_argument("names", nargs="*", help="benchmarks to run (default: all)")
    bench.add_argument("--repeats", type=int, default=3)
    _json_option(bench)
    bench.set_defaults(run=_bench)

    course = commands.add_parser("course", help="build the student notebooks: course build")
    actions = course.add_subparsers(dest="action", required=True, metavar="ACTION")
    build = actions.add_parser(
        "build", help="regenerate course/ from solutions/ (in a checkout of the repository)",
        description="Build the student notebooks in course/ from the solutions.",
        parents=common)
    build.add_argument("--check", action="store_true",
                       help="write nothing; exit 1 if course/ is not what a build would write")
    build.add_argument("--solutions", metavar="DIR",
                       help="solution notebooks (default: solutions, in a checkout's root)")
    build.add_argument("--course", metavar="DIR",
                       help="student notebooks to write (default: course)")
    build.set_defaults(run=_course_build)

    posegraph = commands.add_parser("posegraph", help="optimise a g2o pose graph (sparse LM)",
                                    parents=common)
    posegraph.add_argument("file", help="EDGE_SE2/VERTEX_SE2 graph, .g2o or .g2o.gz, e.g. "
                                        "data/slam/MIT.g2o.gz")
    posegraph.add_argument("--out", metavar="DIR",
                           help=f"folder to write {POSEGRAPH_FILE} in: the graph with its "
                                "optimised poses (default: write nothing)")
    posegraph.add_argument("--robust", choices=["huber", "cauchy"], help="robust kernel")
    posegraph.add_argument("--initial", choices=["chordal", "lago", "given"], default="chordal",
                           help="start from the chordal estimate (default), LAGO's, or the "
                                "file's poses")
    posegraph.add_argument("--max-iterations", type=int, default=100)
    _json_option(posegraph)
    posegraph.set_defaults(run=_posegraph)

    slam = commands.add_parser("slam", help="graph SLAM on a CARMEN laser log", parents=common)
    slam.add_argument("log", help="CARMEN log (.clf or .clf.gz), e.g. data/slam/aces.clf.gz")
    slam.add_argument("--relations", help="benchmark relations file: print the errors")
    slam.add_argument("--out", default="abcwc-slam", metavar="DIR",
                      help="folder for map.yaml, map.pgm and trajectory.txt "
                           "(default: abcwc-slam)")
    slam.add_argument("--max-range", type=float, help="the laser's maximum range (m)")
    slam.add_argument("--laser-offset", type=float, nargs=3, metavar=("X", "Y", "THETA"),
                      help="the laser's pose on the robot (m, m, rad)")
    _json_option(slam)
    slam.set_defaults(run=_slam)

    navtrial = commands.add_parser(
        "navtrial", help="drive the navigator to seeded random goals, judged by ground truth",
        parents=common)
    navtrial.add_argument("--goals", type=int, default=50)
    navtrial.add_argument("--seed", type=int, default=0)
    navtrial.add_argument("--world", default="floor", help="a world's name or a .json file")
    navtrial.add_argument("--no-people", action="store_true", help="without walking people")
    _json_option(navtrial)
    navtrial.set_defaults(run=_navtrial)
    followtrial = commands.add_parser(
        "followtrial", help="the tag follower and A.13's behind Ana in the lab and the "
                            "building, judged by ground truth", parents=common)
    followtrial.add_argument("--seeds", type=int, default=3)
    followtrial.add_argument("--world", default="all", choices=["all", "lab", "building"])
    _json_option(followtrial)
    followtrial.set_defaults(run=_followtrial)

    errands = commands.add_parser(
        "errands", parents=common,
        help="the capstone's trial: the chair maps the floor, then runs errands to seeded "
             "random places among walking people, judged by ground truth")
    errands.add_argument("--count", type=int, default=20)
    errands.add_argument("--seed", type=int, default=0)
    errands.add_argument("--world", default="floor", help="a world's name or a .json file")
    _json_option(errands)
    errands.set_defaults(run=_errands)

    hubtrial = commands.add_parser(
        "hubtrial", parents=common,
        help="classes of N students at once on a JupyterHub on this machine: time per "
             "chapter and memory per server")
    hubtrial.add_argument("--students", default="1,2,4,8",
                          help="class sizes, separated by commas (default: 1,2,4,8)")
    hubtrial.add_argument("--chapter", default="course/00_tour.ipynb",
                          help="the notebook each student runs (default: course/00_tour.ipynb)")
    _json_option(hubtrial)
    hubtrial.set_defaults(run=_hubtrial)

    dashboard = commands.add_parser(
        "dashboard", help="serve the rider's dashboard on the simulated chair as a page "
                          "(Voila) until Ctrl-C", parents=common)
    dashboard.add_argument("--world", default="lab", help="a world's name or a .json file")
    dashboard.add_argument("--port", type=int, default=8866,
                           help="the page's port on 127.0.0.1 (default: 8866)")
    dashboard.add_argument("--no-browser", action="store_true",
                           help="do not open the page in a browser")
    dashboard.set_defaults(run=_dashboard)
    return parser


def error_line(exc: BaseException) -> str:
    """``abcwc: error: <message>`` for a user error, on one line."""
    if isinstance(exc, OSError) and exc.strerror and exc.filename is not None:
        message = f"{exc.filename}: {exc.strerror}"  # not "[Errno 21] Is a directory: ..."
    else:
        message = str(exc) or type(exc).__name__
    lines = (line.strip() for line in message.splitlines())
    return f"{PROG}: error: {' '.join(line for line in lines if line)}"


def bug_line(exc: BaseException) -> str:
    """The one line for an exception that is not the user's mistake."""
    detail = " ".join(str(exc).split())
    raised = type(exc).__name__ + (f": {detail}" if detail else "")
    return (f"{PROG}: internal error: {raised} (a bug in abcwc, not in what you asked for: "
            "please report it; run the command again with --debug to see the traceback)")


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``abcwc`` console script; returns the exit status."""
    args = build_parser().parse_args(sys.argv[1:] if argv is None else argv)
    try:
        return args.run(args)
    except Exception as exc:  # noqa: BLE001 - every error ends in one line, or a traceback
        if args.debug:
            raise
        if isinstance(exc, USER_ERRORS):
            print(error_line(exc), file=sys.stderr)
            return USAGE_ERROR
        print(bug_line(exc), file=sys.stderr)
        return INTERNAL_ERROR


if __name__ == "__main__":
    sys.exit(main())
