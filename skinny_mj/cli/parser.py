"""The ``skinny`` command line.

Every sub-command imports NumPy, MuJoCo and the study it needs when it runs, so ``skinny
--help`` is quick.
User errors (bad files, names, parameters, an ``--out`` that holds results or cannot be a
folder) end with one line on stderr and exit code 2; the machine's (a read-only or full
disk, no rendering backend) with one line and exit code 1.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
from collections.abc import Sequence
from pathlib import Path

from skinny_mj.cli.logs import LEVELS, to_stderr
from skinny_mj.cli.study_help import list_text, study_help
from skinny_mj.errors import SkinnyInputError
from skinny_mj.preflight import check_gl  # imports no mujoco
from skinny_mj.threads import one_blas_thread


class _Parser(argparse.ArgumentParser):
    """argparse that reports a usage error in one line with a pointer to ``--help``
    (exit code 2), instead of the whole usage block before it; a sub-command's
    training-config flags (``config_flags``: a group name in
    :mod:`skinny_mj.cli.config_flags`) are added when it is first used, so that ``skinny
    --help`` does not import the config."""

    config_flags: str | None = None
    body_flags: str | None = None  # a command's --body/--dof: the help's default body

    def _complete(self) -> None:
        name, self.config_flags = self.config_flags, None
        if name is not None:
            from skinny_mj.cli import config_flags

            config_flags.add_flags(self, getattr(config_flags, name))
        default, self.body_flags = self.body_flags, None
        if default is not None:
            from skinny_mj.cli import config_flags

            config_flags.add_body_flags(self, default)

    def format_usage(self) -> str:
        self._complete()
        return super().format_usage()

    def format_help(self) -> str:
        self._complete()
        return super().format_help()

    def error(self, message: str):  # noqa: ANN201 (argparse's signature; never returns)
        self.exit(2, f"{self.prog}: error: {_one_line(message)} "
                     f"(see `{self.prog} --help`)\n")

    def parse_known_args(self, args=None, namespace=None):  # noqa: ANN001, ANN201
        """A sub-command (prog "skinny NAME") names its own unknown arguments, so the
        hint points at its help, not at the top-level one."""
        self._complete()
        namespace, extras = super().parse_known_args(args, namespace)
        if extras and " " in self.prog:
            self.error(f"unrecognized arguments: {' '.join(extras)}")
        return namespace, extras


class _ExperimentHelp(argparse.Action):
    """``skinny experiment NAME --help``: that study's description, rows, groups, runs,
    options and cost; without a NAME (or with ``list``), the command's own help."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, **kwargs):  # noqa: ANN001
        super().__init__(option_strings, dest=dest, default=argparse.SUPPRESS, nargs=0,
                         **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):  # noqa: ANN001
        name = getattr(namespace, "name", None)
        if name in (None, "list"):
            parser.print_help()
            parser.exit()
        os.environ.setdefault("MUJOCO_GL", "disabled")  # before a study imports mujoco
        try:
            text = study_help(name)
        except SkinnyInputError as err:
            parser.exit(2, f"{parser.prog}: error: {_one_line(err)}\n")
        print(text, end="")
        parser.exit()



class _Version(argparse.Action):
    """``skinny --version``: ``skinny <version>`` of the installed distribution, read
    when asked (importlib.metadata), so that building the parser reads no metadata."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, **kwargs):  # noqa: ANN001
        super().__init__(option_strings, dest=dest, default=argparse.SUPPRESS, nargs=0,
                         **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):  # noqa: ANN001
        from importlib.metadata import PackageNotFoundError, version

        try:
            number = version("skinny-mj")
        except PackageNotFoundError:  # run from a source tree that pip never installed
            number = "unknown (not installed)"
        print(f"skinny {number}")
        parser.exit()



def _out_path(text: str) -> Path:
    """argparse type of ``--out``: a path, not empty (``Path("")`` is the current folder:
    an unset shell variable would write there)."""
    if not str(text).strip():
        raise argparse.ArgumentTypeError(f"{text!r} names no file or folder (an unset shell "
                                         "variable?); give one (--out . for here)")
    return Path(text)


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:  # else argparse's "invalid _positive_int value"
        raise argparse.ArgumentTypeError(f"must be a whole number >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a whole number >= 1, got {text}")
    return value


def _rows(text: str) -> str:
    """argparse type of ``--rows``: at least one row id or group (an empty value, as from
    an unset shell variable, would otherwise mean every row)."""
    if not [r for r in text.split(",") if r.strip()]:
        raise argparse.ArgumentTypeError(f"{text!r} names no row: give row ids or groups, "
                                         "or leave --rows out to run every row")
    return text


def _scheduler(text: str) -> str:
    """argparse type of ``--scheduler``: ``local`` or a Dask address."""
    from skinny_mj.engine.sweep import check_scheduler  # only when given: --help stays light

    try:
        return check_scheduler(text)
    except SkinnyInputError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


_UNSET = object()


def given_options(argv: Sequence[str]) -> set[str]:
    """The option dests ``argv`` sets explicitly (not by default): ``--config`` fills
    only the others from its file, so a default never overrides a file's field.

    ``argv`` is parsed again with every sub-command's defaults set to a sentinel
    (``set_defaults``): the dests that do not hold it were on the command line.
    """
    dests = set(vars(build_parser().parse_args(argv)))
    parser = build_parser()
    for sub in parser.subcommands.values():
        sub.set_defaults(**dict.fromkeys(dests, _UNSET))
    return {k for k, v in vars(parser.parse_args(argv)).items() if v is not _UNSET}


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="skinny",
        description="Skinny-MJ: echo state networks learn to make a MuJoCo torso imitate YMCA.",
    )
    parser.add_argument("--version", action=_Version, help="print skinny's version and exit")
    parser.add_argument("--log-level", choices=LEVELS,
                        default="warning", help="the diagnostics shown on stderr (warnings, "
                        "notes; info: progress too); results go to stdout whatever the level")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("demo", help="train with the defaults (paper E, exp. 5) and show the result")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", type=_out_path, help="output folder (default: results/demo/<time>)")

    p = sub.add_parser("track", help="run the analytic ideal controller through the task")
    p.config_flags = "TRACK_FLAGS"
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", type=_out_path, help="output folder (default: results/track/<time>)")

    p = sub.add_parser("train", help="train an ESN inverse model (FEL or true target)",
                       description="Train an ESN inverse model. Settings: TrainConfig's "
                       "defaults (paper E exp. 5; on a torque body without --preset, the torque "
                       "body's own: ESN + FEL with the inertia-scaled PD teacher on the nominal "
                       "model, beta 1, 15 epochs, the forgetting readout, velocities from the "
                       "model-based observer, 3D with 500 units, 6 cycles, poles at 20 rad/s), "
                       "then --preset, then --config FILE, then the "
                       "flags and KEY=VALUE overrides given (any dotted config key, e.g. "
                       "esn.spectral_radius=0.9 method=original method.epochs=2; a metrics.json's "
                       "\"config\" lists them all).")
    p.add_argument("overrides", nargs="*", metavar="KEY=VALUE",
                   help="set any config key (dotted), e.g. esn.leak_rate=0.5")
    p.config_flags = "TRAIN_FLAGS"
    p.add_argument("--seed", type=int, default=argparse.SUPPRESS, help="the run's seed "
                   "(default: the --config file's, else 0)")
    p.add_argument("--out", type=_out_path, help="output folder (default: results/train/<time>)")
    p.add_argument("--config", type=Path, help="repeat a run: its metrics.json (or a bare "
                   "config JSON of dotted keys); flags given as well override its settings")
    p.add_argument("--preset", choices=("general",), help="a named configuration; flags "
                   "given as well override its settings. general: the inverse model for "
                   "unseen movements, one per --body and --signals (default: 2D, joint "
                   "angles): motor babbling over every joint's whole range, its limits "
                   "and rests, full scale 4x its fastest speed (3D Cartesian: 240 s of "
                   "babbling then YMCA, 2x), paper E exp. 5 schedule; the configuration "
                   "with the lowest error on real dance it never saw in `skinny experiment "
                   "generalization --rows general`. Trained ones ship (general-2d-joint, "
                   "general-3d-joint, general-2d-cartesian, general-3d-cartesian): skinny "
                   "test --model general-2d-joint --trajectory md_02.amc (a shipped clip; "
                   "another CMU clip: --trajectory CLIP.amc --asf SUBJECT.asf). "
                   "On a torque body: the torque twin's general, one per body (joint "
                   "angles): 240 s of babbling at 0.5-4 rad/s (within the torque limits) then "
                   "YMCA, the inertia-scaled PD teacher (3D: poles at 20 rad/s, forgetting "
                   "0.9), the forgetting readout; trained ones ship (general-2d-torque, "
                   "general-3d-torque)")

    p = sub.add_parser("test", help="run a saved model (K = 0) on a movement")
    p.add_argument("--model", type=Path, required=True, help="model.npz written by `skinny "
                   "train`, or a shipped general model: general-2d-joint, general-3d-joint, "
                   "general-2d-cartesian, general-3d-cartesian; on the torque bodies "
                   "general-2d-torque, general-3d-torque")
    p.config_flags = "TEST_FLAGS"
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", type=_out_path, help="output folder (default: results/test/<time>)")

    p = sub.add_parser("trajectory", help="list or export movements")
    tsub = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    tsub.add_parser("list", help="every movement source: the named movements, the shipped "
                    "clips, the file kinds, babble: and set:")
    w = tsub.add_parser("show", help="a movement's statistics (still steps, peak speeds, "
                        "unreachable targets, tremor band)")
    w.add_argument("name")
    w.body_flags = "2d"
    w.add_argument("--asf", type=Path)
    w.add_argument("--retarget", choices=("angles", "positions"), default="angles")
    w.add_argument("--actuation", choices=("velocity", "torque"), default="velocity",
                   help="torque: also the torques the movement needs on the torque twin")
    e = tsub.add_parser("export", help="write a movement to .npz or .csv")
    e.add_argument("name")
    e.body_flags = "2d"
    e.add_argument("--asf", type=Path)
    e.add_argument("--speed", type=float, default=1.0)
    e.add_argument("--reps", type=_positive_int, default=1)
    e.add_argument("--out", type=_out_path, required=True, help="FILE.npz or FILE.csv")
    e.add_argument("--overwrite", action="store_true", help="replace --out if it exists")

    p = sub.add_parser("experiment", help="reproduce a paper's table and figures (a sweep)",
                       add_help=False)
    p.add_argument("-h", "--help", action=_ExperimentHelp, help="this help; after a NAME: "
                   "that study's rows, groups, runs, options and cost")
    p.add_argument("name", help="experiment name (`skinny experiment list` shows them), "
                   "or `list`")
    p.add_argument("--runs", type=_positive_int, help="runs per row (default: the paper's)")
    p.add_argument("--workers", type=_positive_int, help="parallel processes (default: all cores)")
    p.add_argument("--out", type=_out_path, help="output folder (default: results/<name>/<time>)")
    p.add_argument("--resume", action="store_true", help="continue the sweep in --out: skip "
                   "its ok and failed runs, rerun errored ones (rows may differ)")
    p.add_argument("--overwrite", action="store_true", help="replace the sweep already in "
                   "--out (without it, a non-empty --out is refused)")
    p.add_argument("--quick", action="store_true", help="a smoke test: few runs, few epochs")
    p.add_argument("--scheduler", type=_scheduler,
                   help="Dask scheduler: `local` or tcp://HOST:PORT")
    p.add_argument("--movement", help="train/test every row on another movement (name or "
                   "file; default: the paper's); recorded in config.json, the name stays")
    p.add_argument("--asf", type=Path, help="ASF skeleton for an .amc --movement")
    p.body_flags = "the paper's"
    p.add_argument("--signals", choices=("joint", "cartesian"),
                   help="the networks' position signals (default: the paper's)")
    p.add_argument("--rows", type=_rows, help="comma-separated row ids and groups to run "
                   "(default: all); seeds are the full sweep's")
    p.add_argument("--config", type=Path, help="repeat a sweep: its config.json (options, "
                   "rows, runs); flags given as well override them")
    p.add_argument("--protocol", help="run the study under a named set of readings of the "
                   "thesis's unstated settings (`thesis`: the recorded-like YMCA, u_error gain "
                   "2, ...; `gain-0.5`, `gain-2`: the u_error scale's band; `b-noise-free`: "
                   "paper B's reservoir without noise; a study's --help lists those that read "
                   "its settings)")

    p = sub.add_parser("sweep", help="a grid over any config keys on the experiment engine: "
                       "skinny sweep esn.spectral_radius=0.5,0.9 --runs 20")
    p.add_argument("axes", nargs="+", metavar="KEY=V1,V2", help="a config key and its values "
                   "(quote a value holding a comma: KEY='a,b',c); rows are the product of the "
                   "keys with several values, a key with one value changes every row")
    p.add_argument("--runs", type=_positive_int, help="runs per row (default 10; with "
                   "--quick, the study's --quick runs or 2)")
    p.add_argument("--study", help="start from a study's row (with --row): its config, "
                   "metrics and run (default: paper E exp. 5, TrainConfig's defaults)")
    p.add_argument("--row", help="the --study row to start from")
    p.add_argument("--config", type=Path, help="start from a config file: a run's "
                   "metrics.json or a bare config (instead of TrainConfig's defaults)")
    p.add_argument("--quick", action="store_true", help="a smoke test: the --study's own "
                   "--quick for its row, else 2 epochs; 2 runs per row unless --runs")
    p.add_argument("--rows", type=_rows, help="comma-separated row ids to run (default: all)")
    p.add_argument("--workers", type=_positive_int, help="parallel processes (default: all cores)")
    p.add_argument("--out", type=_out_path, help="output folder (default: results/sweep/<time>)")
    p.add_argument("--resume", action="store_true", help="continue the sweep in --out")
    p.add_argument("--overwrite", action="store_true", help="replace the sweep in --out")
    p.add_argument("--scheduler", type=_scheduler,
                   help="Dask scheduler: `local` or tcp://HOST:PORT")

    p = sub.add_parser("claims", help="score every thesis claim from sweeps' run files "
                       "(holds / does not hold / not testable, with the numbers)",
                       description="Score the thesis's claims (experiments/claims_catalogue.py) "
                       "by the declared rules (experiments/claims_rules.py) over the run files "
                       "of the sweeps given, under each reading column they cover; a band "
                       "reading (gain-band) takes one --from per point. `skinny claims --plan` "
                       "prints the command of every sweep the claims read.")
    p.add_argument("--plan", action="store_true", help="print the `skinny experiment` command "
                   "of every sweep the claims read (the thesis's run counts), then the "
                   "`skinny claims` line that scores them all, and stop")
    p.add_argument("--from", dest="sources", action="append",
                   metavar="STUDY[:READINGS]=FOLDER", help="a sweep's folder (or its extract's "
                   ".json) and the study (and reading column, e.g. paper-e:recorded) its runs "
                   "are; repeat it")
    p.add_argument("--extracts", type=Path, metavar="DIR", help="score the extracts in DIR "
                   "(written by --extract) instead of sweeps' folders")
    p.add_argument("--extract", type=Path, metavar="DIR", help="write each sweep's extract "
                   "into DIR (per row and run: seed, status, the metrics the claims read; "
                   "small enough to commit)")
    p.add_argument("--page", type=Path, metavar="FILE", help="replace the computed section "
                   "of the results page FILE (between its claims-computed markers)")
    p.add_argument("--out", type=Path, help="folder for claims.md and claims.json "
                   "(default: results/claims/<time>, unless --page)")
    p.add_argument("--overwrite", action="store_true", help="replace claims.md and "
                   "claims.json in --out")

    p = sub.add_parser("bench", help="measure the fast path: ratios vs reservoirpy, physics, "
                       "the naive loop (prints a table)")
    p.add_argument("--quick", action="store_true", help="short timings; no full paper-E sweep")
    p.add_argument("--out", type=_out_path, help="write every figure to FILE.json")
    p.add_argument("--workers", type=_positive_int,
                   help="processes for paper_e_full_s (default: all cores)")

    p = sub.add_parser("render", help="render Skinny to a PNG (needs MUJOCO_GL=egl)")
    p.body_flags = "2d"
    p.add_argument("--trajectory", help="pose Skinny at a movement's frame (default: rest pose)")
    p.add_argument("--frame", type=int, default=0)
    p.add_argument("--width", type=_positive_int, default=640)
    p.add_argument("--height", type=_positive_int, default=480)
    p.add_argument("--out", type=_out_path, required=True)

    p = sub.add_parser("view", help="open a recording (or a results folder's) in the rerun "
                       "viewer; headless, print the command (or save a --screenshot)")
    p.add_argument("path", type=Path, help="a .rrd file or a folder holding some")
    p.add_argument("--web", action="store_true",
                   help="serve the web viewer (on --bind: 127.0.0.1, this machine only)")
    p.add_argument("--web-port", type=_positive_int, default=9090, help="HTTP port for --web")
    p.add_argument("--grpc-port", type=_positive_int, default=9876,
                   help="port of the viewer's gRPC server (the web viewer reads its data there)")
    p.add_argument("--bind", default="127.0.0.1",
                   help="address the viewer listens on (default 127.0.0.1: this machine only; "
                   "0.0.0.0: every interface)")
    p.add_argument("--dry-run", action="store_true", help="print the viewer command only")
    p.add_argument("--screenshot", type=Path, metavar="OUT.png",
                   help="save the viewer's picture of the recording to OUT.png instead (no "
                   "display needed: a headless viewer, drawing with Vulkan)")
    p.add_argument("--at", type=float, default=0.0, metavar="SECONDS",
                   help="with --screenshot: the time cursor's place, s (default 0)")

    for name in ("demo", "train", "experiment", "sweep", "bench"):  # the long commands
        sub.choices[name].add_argument(
            "--quiet", "-q", action="store_true",
            help="no progress bar (also off when stderr is not a terminal)")
    for name in ("demo", "track", "train", "test"):  # a run's folder
        sub.choices[name].add_argument(
            "--overwrite", action="store_true", help="replace the run already in --out "
            "(without it, an --out holding files is refused; a folder of other files always is)")
    for name in ("bench", "render"):
        sub.choices[name].add_argument("--overwrite", action="store_true",
                                       help="replace --out if it exists")
    parser.subcommands = sub.choices  # name -> sub-command parser (for given_options)
    return parser


def _one_line(err: BaseException) -> str:
    return " ".join(str(err).split()) or type(err).__name__


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill PID``, a batch system's time limit), raised like Ctrl-C so that a
    sweep stops its worker processes and releases its lock on the way out."""


def _terminate(signum: int, frame: object) -> None:
    raise Terminated


def _on_sigterm(handler: object) -> object:
    """Install ``handler`` for SIGTERM, returning the one it replaces (None, and nothing
    installed, off the main thread or where another handler than the default is set)."""
    import threading

    if handler is None or threading.current_thread() is not threading.main_thread():
        return None
    current = signal.getsignal(signal.SIGTERM)
    if handler is _terminate and current is not signal.SIG_DFL:
        return None  # an embedding program's own handler stays
    signal.signal(signal.SIGTERM, handler)
    return current


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parser.parse_args(argv)
    if args.command == "experiment" and args.config is not None:
        args.given = given_options(argv)  # which flags override the file
        if "dof" in args.given:  # --dof is --body by its number of hinges
            args.given.add("body")
    # Choose the GL backend before mujoco/dm_control are imported: no pixels unless rendering.
    if not os.environ.get("MUJOCO_GL", "").strip():  # unset, or set empty (`MUJOCO_GL= skinny`)
        os.environ["MUJOCO_GL"] = "egl" if args.command == "render" else "disabled"
    previous = _on_sigterm(_terminate)
    restore_logs = to_stderr(args.log_level)  # diagnostics: plain lines on stderr
    try:
        if args.command == "experiment" and args.name == "list":  # reads the studies' source:
            # no NumPy, no study
            print(list_text())
            sys.stdout.flush()
            return 0
        check_gl()  # a MUJOCO_GL mujoco refuses would fail at its import, as a traceback
        from skinny_mj.cli import commands  # imports mujoco
        from skinny_mj.cli.flags import check_args

        check_args(args)  # every numeric flag in its range (seed >= 0, ...), before any work
        with one_blas_thread():  # same bits whatever the machine's BLAS threads
            code = int(getattr(commands, f"cmd_{args.command}")(args) or 0)
        sys.stdout.flush()  # a closed pipe shows here, not as exit 120 at shutdown
        return code
    except SkinnyInputError as err:
        print(f"skinny {args.command}: error: {_one_line(err)}", file=sys.stderr)
        return 2
    except ValueError as err:
        if "null byte" not in str(err):  # a NUL in a name (argv from Python, a config file)
            raise
        print(f"skinny {args.command}: error: a file name holds a NUL byte ({err})",
              file=sys.stderr)
        return 2
    except BrokenPipeError:  # the reader stopped reading (`skinny experiment list | head`)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no error at exit
        return 0
    except OSError as err:  # the machine, not the input: unwritable or full disk, no GL,
        # no model folder, an unreachable scheduler, a worker killed (SkinnyEnvironmentError)
        print(f"skinny {args.command}: error: {_one_line(err)}", file=sys.stderr)
        return 1
    except Terminated:
        print("terminated", file=sys.stderr)
        return 143
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    finally:
        _on_sigterm(previous)
        restore_logs()


if __name__ == "__main__":
    sys.exit(main())
