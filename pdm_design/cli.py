"""The `pdm-design` command line: a thin layer over pdm_design.api.

Heavy modules (the spec loader, scipy, casadi, matplotlib) are imported inside the commands so
that `pdm-design --help` starts fast. Exit codes: 0 success, 1 infeasible / verification failed /
expectation not met, 2 bad input. Errors are one clear message, never a traceback (set
PDM_DESIGN_DEBUG=1 to see one for an internal error).
"""

from __future__ import annotations

import functools
import json
import os
import sys

import click

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2


def _guarded(command):
    """Map every error to a message on stderr and the documented exit code."""

    @functools.wraps(command)
    def wrapper(*args, **kwargs):
        from .errors import OutputError, PdmError, SpecError

        try:
            code = command(*args, **kwargs)
        except (SpecError, OutputError) as error:
            click.echo(f"error: {error}", err=True)
            machine = isinstance(error, OutputError) and not error.bad_input  # a full disk
            sys.exit(EXIT_FAILED if machine else EXIT_BAD_INPUT)
        except PdmError as error:
            click.echo(f"error: {error}", err=True)
            sys.exit(EXIT_FAILED)
        except (click.exceptions.Exit, click.ClickException, SystemExit, KeyboardInterrupt):
            raise
        except BrokenPipeError:  # the reader of stdout stopped (`| head`): not an internal error
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # (and at exit)
            click.echo("error: stdout was closed before all the output was written (its reader "
                       "stopped early)", err=True)
            sys.exit(EXIT_FAILED)
        except Exception as error:
            if os.environ.get("PDM_DESIGN_DEBUG"):
                raise
            said = str(error).rstrip().rstrip(".")  # one full stop before the request
            click.echo(f"internal error ({type(error).__name__}): {said}. "
                       "Please report it with the spec that caused it.", err=True)
            sys.exit(EXIT_FAILED)
        sys.exit(code or EXIT_OK)

    return wrapper


FORMAT = click.option("--format", "fmt", type=click.Choice(["text", "json"]), default="text",
                      show_default=True, help="Readable report, or one JSON document on stdout.")
# A plain string: the spec loader says what is wrong with it (a directory, no such file) in the
# tool's words.
SPEC = click.argument("spec", type=str)


class _Count(click.ParamType):
    """An integer from `low` to `high`, refused in the tool's words (click.IntRange's are
    click's)."""

    name = "integer"

    def __init__(self, low: int, high: int):
        self.low, self.high = low, high

    def convert(self, value, param, ctx):
        try:
            number = int(value, 10) if isinstance(value, str) else value
        except ValueError:
            number = None
        if isinstance(number, bool) or not isinstance(number, int) \
                or not self.low <= number <= self.high:
            self.fail(f"expected an integer from {self.low} to {self.high}, found {value!r}",
                      param, ctx)
        return number


class _Main(click.Group):
    """The command group. A bad option value or a usage mistake is reported as every other bad
    input is: `error: command line: OPTION: what was expected`, exit 2 (not click's usage
    text)."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except click.UsageError as error:
            click.echo(f"error: command line: {_usage_words(error)}", err=True)
            sys.exit(EXIT_BAD_INPUT)


def _usage_words(error: click.UsageError) -> str:
    """`OPTION: what was expected` for a bad value; click's sentence and where to look for a
    missing argument or an unknown option or command."""
    param = getattr(error, "param", None)
    if isinstance(error, click.BadParameter) and not isinstance(error, click.MissingParameter) \
            and param is not None:
        name = param.opts[0] if isinstance(param, click.Option) else param.human_readable_name
        return f"{name}: {error.message}"
    command = error.ctx.command_path if error.ctx is not None else "pdm-design"
    return f"{error.format_message().rstrip('.')} (see `{command} --help`)"


@click.group(cls=_Main, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="pdm-design")
def main():
    """Design passive dynamic object manipulation systems (each installed scene: a device and
    the object it moves)."""


class _AccuracyType(click.ParamType):
    """--accuracy: a preset name or KEY=VALUE tolerances. A bad value is a usage error (exit 2)
    raised while click parses the options, before any command (or _guarded) runs."""

    name = "accuracy"

    def convert(self, value, param, ctx):
        from .accuracy import Accuracy, AccuracyError, accuracy_from_text

        if isinstance(value, Accuracy):
            return value
        try:
            return accuracy_from_text(value)
        except AccuracyError as error:
            self.fail(error.detail, param, ctx)


ACCURACY = click.option(
    "--accuracy", type=_AccuracyType(), default=None, metavar="PRESET|KEY=VALUE,...",
    help="Simulator tolerances: fast, default or precise, or KEY=VALUE pairs (keys rtol, atol, "
    "event_tol, agreement; base: the preset giving the rest and the optimizer's settings, "
    "default 'default'), e.g. rtol=1e-10,agreement=1e-8. Default: the spec's.")


class _KindType(click.ParamType):
    """An installed scene's kind, looked up when the command runs (entry-point metadata only:
    no scene is imported to list them)."""

    name = "kind"

    def convert(self, value, param, ctx):
        from .errors import did_you_mean
        from .plugin import kinds

        if value not in kinds():
            self.fail(f"{value!r} is not an installed scene (installed: {', '.join(kinds())})"
                      f"{did_you_mean(value, kinds())}", param, ctx)
        return value


@main.command()
@click.argument("kind", type=_KindType())
@click.option("--out", default=None, metavar="FILE",
              help="Write the spec to FILE (not over an existing file; in an existing "
              "folder) instead of stdout.")
@_guarded
def init(kind, out):
    """A commented spec to start from for the installed scene KIND (the scene's own, its
    initial state one its design runs from). It optimizes as written."""
    from .plugin import scene_kind

    text = scene_kind(kind).template()
    if out is None:
        click.echo(text, nl=False)
        return EXIT_OK
    from pathlib import Path

    from .errors import SpecError
    from .io import check_output, write_atomic

    if Path(out).exists() or not out:
        raise SpecError("command line", "--out", "the name of a file that does not exist yet "
                        "(init does not overwrite)", repr(out))
    check_output(out, "--out", new_folders=False)
    write_atomic(out, text)
    click.echo(f"wrote {out}: a {kind} spec; next: pdm-design optimize {out}")
    return EXIT_OK


@main.command()
@SPEC
@FORMAT
@ACCURACY
@click.option("--no-verify", is_flag=True, help="Skip the simulator's verification.")
@click.option("--linearised", is_flag=True, help="Also the largest boxes and ellipsoid in the "
              "linearised safe set of offsets (cvxpy; first-order, beside the robust box).")
@_guarded
def optimize(spec, fmt, accuracy, no_verify, linearised):
    """Solve SPEC: choose the free design variables (or evaluate a fixed design), verify, report."""
    from .api import design
    from .spec import load_spec

    outcome = design(load_spec(spec), verify=not no_verify, accuracy=accuracy,
                     linearise=linearised)
    if fmt == "json":
        from .report.document import optimize_document

        click.echo(json.dumps(optimize_document(outcome), indent=2))
    else:
        from .report.text import optimize_text

        click.echo(optimize_text(outcome), nl=False)
    return outcome.exit_code


def _parse_pairs(values, label, what, count):
    """Parse 'K:A,B' options (1 <= K <= count, each K once) into (K, A, B), or a clear error
    naming the option. A and B are lengths, held to the spec loader's limit: a larger one would
    fail the model's validation with a dump instead of a message."""
    from .errors import SpecError
    from .scenes.common import LARGEST

    parsed, seen = [], set()
    for text in values:
        try:
            index, pair = text.split(":", 1)
            first, second = (float(v) for v in pair.split(","))
            index = int(index)
            if not 1 <= index <= count or not all(abs(v) <= LARGEST for v in (first, second)):
                raise ValueError  # (abs(nan) <= LARGEST is False: nan and inf are refused too)
        except ValueError:
            raise SpecError("command line", label, f"{what} with K from 1 to {count} and "
                            f"values within +-{LARGEST:g} m, e.g. 2:0.1,-0.2", repr(text)) from None
        if index in seen:  # as the spec loader refuses for its offsets and step_errors
            raise SpecError("command line", label, "each K listed once",
                            f"K = {index} again in {text!r}")
        seen.add(index)
        parsed.append((index, first, second))
    return parsed


def _with_spec_items(spec_items, given: dict, index: str, key: str, row: int, spec: str):
    """The spec's offsets (or step errors) with the command line's in place of those of the
    same K. One of the spec's beyond a shorter --stages row is refused, not dropped: the run
    would silently be another build than the spec's."""
    from .errors import SpecError

    merged = {getattr(item, index): item for item in spec_items}
    beyond = [k for k in merged if k > row and k not in given]
    if beyond:
        raise SpecError("command line", "--stages", f"at least {max(beyond)}: {spec}'s {key} "
                        f"set {index} {max(beyond)}", str(row))
    merged.update(given)
    return tuple(merged[k] for k in sorted(merged))


def _check_plot_path(plot: str) -> None:
    """Refuse a --plot file whose extension matplotlib cannot write, before any work (matplotlib
    picks the format from the extension; it is imported only here: it is slow to import)."""
    from pathlib import Path

    from matplotlib.figure import Figure

    from .errors import SpecError

    formats = dict(Figure().canvas.get_supported_filetypes())
    import shutil

    import matplotlib

    if not shutil.which(matplotlib.rcParams["pgf.texsystem"]):  # pgf typesets with LaTeX
        formats.pop("pgf", None)
    if Path(plot).suffix[1:].lower() not in formats:
        raise SpecError("command line", "--plot", "a file name ending in .png, .svg, .pdf or "
                        f"another format matplotlib writes ({', '.join(sorted(formats))})",
                        repr(plot))
    if Path(plot).is_dir():
        raise SpecError("command line", "--plot", "a file name", f"{plot!r}, a directory")
    from .io import check_output

    check_output(plot, "--plot")


# The files each command always writes into its output folder (checked before any work:
# io.check_output); the sheet's drawing files unless --no-drawing
OUTPUT_FILES = {
    "table": ("table.csv", "table.md", "sweep.json"),
    "sheet": ("sheet.md", "sheet.csv"),
    "report": ("report.html",),
    "yield": ("yield.json", "survival.png"),
}
DRAWING_FILES = ("sheet.png", "sheet.svg", "sheet.pdf", "sheet.dxf", "sheet_dxf.png")


def _out_folder(out: str | None, source: str, command: str, more: tuple[str, ...] = ()) -> str:
    """The output folder of `command` (--out, else the default named after the source),
    refused before any work when it cannot be written (exit 2)."""
    from .io import check_output

    folder = out if out is not None else f"{_default_name(source)}-{command}"
    check_output(folder, "--out", folder=True, names=OUTPUT_FILES[command] + more)
    return folder


def _default_name(source: str) -> str:
    """What a default output folder is named after: the spec's `name` when it gives one that
    is a plain file name (letters, digits, '.', '_', '-'), else the file's name without its
    extension. A saved optimize JSON gives its spec's name; a source that cannot be read is
    named by its file (the command then says what is wrong with it)."""
    import re
    from pathlib import Path

    from .errors import SpecError

    try:
        if Path(source).suffix.lower() == ".json":
            doc = json.loads(Path(source).read_text(encoding="utf-8"))
            name = doc.get("name") if isinstance(doc, dict) else ""
        else:
            from .spec import load_spec

            name = load_spec(source).name
    except (OSError, ValueError, SpecError):  # the command says what is wrong with it
        name = ""
    plain = isinstance(name, str) and re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._-]*", name)
    return name if plain else Path(source).stem


def _refuse_other_stage_errors(scene, given: dict) -> None:
    """Each per-stage error option is refused, not ignored, on a scene that takes another: a
    run without the errors the user asked for would look like their answer."""
    from .errors import SpecError
    from .plugin import kinds, scene_kind

    own = scene.stage_errors.option if scene.stage_errors else None
    for option, values in given.items():
        if not values or option == own:
            continue
        takers = [k for k in kinds()
                  if getattr(scene_kind(k).stage_errors, "option", None) == option]
        for_whom = " or ".join(takers) or "no installed"
        rest = f"{scene.kind} take {own}" if own else f"{scene.kind} takes no per-stage errors"
        raise SpecError("command line", option, f"a {for_whom} spec ({option} is for "
                        f"{for_whom} scenes; {rest})", f"a {scene.kind} spec")


@main.command()
@SPEC
@click.option("--stages", type=_Count(1, 10_000_000), default=None,
              help="Stages to run, in the scene's own unit (default: the spec's "
              "verification.stages; at least the highest K of the spec's per-stage errors).")
@click.option("--offset", "offsets", multiple=True, metavar="K:DX,DY",
              help="Offset stage K's pivot (from 1) by DX, DY metres (y up), in place of the "
              "spec's offset for K; the spec's others stay. Repeatable.")
@click.option("--step-error", "step_errors", multiple=True, metavar="K:DRISE,DTREAD",
              help="Add DRISE, DTREAD metres to step K's rise and tread, in place of the spec's "
              "error for K; the spec's others stay. Repeatable.")
@click.option("--plot", type=str, default=None, metavar="FILE",
              help="Write figures like the paper's to this file; its extension picks the "
              "format (png, svg, pdf, ...).")
@click.option("--build", default=None, metavar="SEED:INDEX",
              help="Run build INDEX of `pdm-design yield --seed SEED` (its parts as drawn from "
              "the spec's [tolerances]; give the same --stages).")
@click.option("--from", "saved", default=None, metavar="FILE",
              help="Take the design from FILE instead of solving: a `pdm-design yield` run's "
              "yield.json or --out folder (with --build: also its tolerances and stages) or a "
              "saved `optimize --format json`; it must be of SPEC as it is now.")
@ACCURACY
@FORMAT
@_guarded
def simulate(spec, stages, offsets, step_errors, plot, accuracy, fmt, build, saved):
    """Run the event simulator on SPEC's design (optimised first if it has free variables,
    unless --from gives it; when no design meets every requirement, its least-violation design
    is run, with a warning, and the exit code is 1)."""
    from .api import design
    from .errors import PdmError, SpecError
    from .plugin import of
    from .report.simulation import simulation_text
    from .sim.core import SimulationRefused
    from .spec import load_spec
    from .verify import simulate_spec

    if plot is not None:
        _check_plot_path(plot)
    loaded = load_spec(spec)
    if saved is not None:
        from .saved import read_saved_design

        saved = read_saved_design(saved, loaded, spec)
        if stages is None and build is not None and saved.stages is not None:
            stages = saved.stages  # the yield run's: the build as it drew it
    scene = of(loaded)
    _refuse_other_stage_errors(scene, {"--offset": offsets, "--step-error": step_errors})
    most, why = scene.stage_limit(False)
    if stages is not None and stages > most:
        raise SpecError("command line", "--stages", f"at most {most} "
                        f"{scene.stage_noun[1]} ({why})", str(stages))
    row = stages or loaded.verification.stages
    built = None  # the per-stage build errors of the run (None: the scene takes none)
    errors = scene.stage_errors
    if errors is not None:
        typed = {"--offset": offsets, "--step-error": step_errors}[errors.option]
        given = {k: errors.item(k, a, b) for k, a, b in
                 _parse_pairs(typed, errors.option, errors.metavar, row)}
        built = _with_spec_items(loaded.verification.stage_list(errors.key), given,
                                 errors.index, f"verification.{errors.key}", row, spec)
    point, answered, found = loaded.design_at(), True, None
    if saved is not None:
        point, answered = saved.point, saved.success
        if not answered:
            click.echo(f"warning: {saved.source}: its design does not meet every requirement "
                       f"(status {saved.status}); simulating it", err=True)
    elif loaded.free_variables:
        found = design(loaded, verify=False)
        point, answered = loaded.design_at(found.analysis.design), found.status.is_success
        if not answered:  # the run below is of no answer: say so, and exit 1
            click.echo(f"warning: {spec}: the optimizer found no design that meets every "
                       f"requirement (status {found.status.value}); simulating its "
                       "least-violation design", err=True)
    if build is not None and (offsets or step_errors):
        raise SpecError("command line", "--build", f"no {errors.option} with it (the build's "
                        "parts are drawn)", "both")
    try:
        if build is not None:
            from .commands.yield_ import simulate_build_of_spec

            result = simulate_build_of_spec(
                loaded, spec, point, build, row, accuracy=accuracy,
                record_trajectory=plot is not None,
                tolerances=saved.tolerances if saved is not None else None, answer=found)
            if plot is not None and result.events and result.events[0].kind == "invalid_part":
                click.echo("no figures: the build has a part that cannot be made", err=True)
                plot = None
        else:
            result = simulate_spec(loaded, point, stages=stages, accuracy=accuracy,
                                   record_trajectory=plot is not None, errors=built)
    except SimulationRefused as refusal:  # the design is at fault, not the input's syntax: exit 1
        raise PdmError(f"{spec}: the simulator refuses this design: {refusal}") from None
    if plot is not None:
        from .report.plots import plot_simulation

        plot_simulation(loaded, point, result, plot, stages=stages,
                        offsets=built or ())
    if fmt == "json":
        from .report.jsonable import jsonable

        click.echo(json.dumps(jsonable(result.to_json()), indent=2))
    else:
        click.echo(simulation_text(loaded, result), nl=False)
    if plot is not None:  # stdout stays one JSON document with --format json
        click.echo(f"figures written to {plot}", err=fmt == "json")
    return EXIT_OK if result.outcome.completed and answered else EXIT_FAILED


@main.command()
@SPEC
@click.option("--sweep", "sweeps", multiple=True, required=True,
              metavar="NAME=START:STOP:COUNT",
              help="Sweep a numeric parameter of the spec (by key name, e.g. mass_ratio, "
              "friction, or dotted path, e.g. scene.body.width) over COUNT evenly spaced values "
              "from START to STOP. Repeat for a grid.")
@click.option("--out", type=click.Path(file_okay=False, path_type=str), default=None,
              help="Folder for table.csv, table.md, sweep.json and the plots, PNG and SVG, "
              "and a scene's own files (a slope sweep's bifurcations.json and "
              "bifurcation.png, where the scene writes them) (default: the spec's name, else "
              "its file's, followed by -table).")
@click.option("--resume", is_flag=True,
              help="Keep the rows an interrupted run left in --out and solve only the rest.")
@click.option("--workers", type=_Count(1, 4096), default=None,
              help="Local worker processes (default: the machine's cores; 1: in this process).")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Run on an existing Dask distributed cluster (scheduler address, e.g. "
              "tcp://10.0.0.5:8786) instead of local workers.")
@click.option("--chain", type=_Count(1, 1_000_000), default=4, show_default=True,
              help="Grid points solved in sequence, each warm-started from the one before.")
@click.option("--no-plots", is_flag=True, help="Write the tables only.")
@_guarded
def table(spec, sweeps, out, resume, workers, scheduler, chain, no_plots):
    """Design table: solve SPEC at every point of a parameter grid; write CSV (row by row, as
    points finish), Markdown and plots. Exit 0 when every point was solved (infeasible points
    are rows with their reason), 1 if a point failed to solve or the run was interrupted."""
    from pathlib import Path

    from .sweep.run import run_sweep

    folder = _out_folder(out, spec, "table")
    try:
        result = run_sweep(spec, sweeps, folder, workers=workers, scheduler=scheduler,
                           resume=resume, chain=chain, plots=not no_plots)
    except KeyboardInterrupt:
        import signal

        from .sweep.interrupts import STOP_SIGNALS

        # the command is ending with its rows whole: a further Ctrl-C (or SIGTERM) while Python
        # shuts down must not kill it (exit -2 instead of 1)
        for signum in STOP_SIGNALS:
            signal.signal(signum, signal.SIG_IGN)
        click.echo(f"interrupted: the rows solved so far are in {Path(folder) / 'table.csv'}; "
                   "run the same command with --resume to continue", err=True)
        return EXIT_FAILED
    statuses = {}
    for row in result.rows:
        statuses[row["status"]] = statuses.get(row["status"], 0) + 1
    counts = ", ".join(f"{n} {s}" for s, n in sorted(statuses.items()))
    click.echo(f"{len(result.rows)} points ({counts}); {result.computed} solved now, "
               f"{result.reused} kept from before")
    for path in result.files:
        click.echo(f"  {path}")
    return EXIT_FAILED if result.errors else EXIT_OK


@main.command()
@click.argument("source", metavar="SPEC_OR_JSON", type=str)
@click.option("--out", type=click.Path(file_okay=False, path_type=str), default=None,
              help="Folder for sheet.md, sheet.csv, the drawing (sheet.png, sheet.svg, sheet.pdf), "
              "sheet.dxf and its rendering sheet_dxf.png (default: the spec's name, else the "
              "source file's, followed by -sheet).")
@click.option("--count", type=_Count(1, 10_000_000), default=None,
              help="Stages listed, one item each (default: the spec's verification.stages; the "
              "tolerance covers only the first verification.stages of them).")
@click.option("--no-tolerance", is_flag=True,
              help="Do not solve for the placement tolerance when the design carries none.")
@click.option("--no-drawing", is_flag=True,
              help="Write the Markdown and CSV only (an earlier drawing and DXF in the "
              "folder is removed).")
@_guarded
def sheet(source, out, count, no_tolerance, no_drawing):
    """Build sheet of a design: a spec (solved first) or a saved `optimize --format json`
    document. What a workshop places for every stage (a pivot's coordinates, a step's rise
    and tread), each with its tolerance, and the parts list; Markdown, CSV and a dimensioned
    drawing. Exit 1 (sheet still written) when the design does not work."""
    from .plugin import of
    from .sheet import sheet_for, write_sheet

    folder = _out_folder(out, source, "sheet", () if no_drawing else DRAWING_FILES)
    built = sheet_for(source, count=count, tolerance=not no_tolerance)
    files = write_sheet(built, folder, drawing=not no_drawing)
    what = of(built.spec).stage_noun[1]
    click.echo(f"build sheet of {built.count} {what} (status {built.status}; tolerance: "
               f"{built.tolerance_note})")
    if built.tolerance and built.tolerance_covers < built.count:
        click.echo(f"note: the tolerance holds for {what} 1 to {built.tolerance_covers} only "
                   "(the spec's verification.stages); the sheet says how to get it for all")
    for path in files:
        click.echo(f"  {path}")
    if built.failures:
        click.echo("warning: this design does not work; the sheet is written with this "
                   "warning at its top:", err=True)
        for failure in built.failures:
            click.echo(f"  {failure}", err=True)
        return EXIT_FAILED
    return EXIT_OK


@main.command(name="yield")
@SPEC
@click.option("--builds", type=_Count(1, 10_000_000), default=None,
              help="Builds drawn (default: the spec's tolerances.builds).")
@click.option("--stages", type=_Count(1, 100_000), default=None,
              help="Stages each build must pass (default: the spec's verification.stages).")
@click.option("--seed", type=_Count(0, 2**63 - 1), default=None,
              help="Random seed of the builds (default: the spec's tolerances.seed).")
@click.option("--out", type=click.Path(file_okay=False, path_type=str), default=None,
              help="Also write yield.json, survival.png, yield_scale.png and sensitivity.png "
              "to this folder.")
@ACCURACY
@FORMAT
@click.option("--workers", type=_Count(1, 4096), default=None,
              help="Local worker processes the event simulator runs the builds on (default: "
              "the spec's tolerances.workers, else the machine's cores; 1: in this process). "
              "The results do not depend on it.")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Run the simulated builds on an existing Dask distributed cluster "
              "(scheduler address, e.g. tcp://10.0.0.5:8786) instead of local workers.")
@_guarded
def yield_command(spec, builds, stages, seed, out, accuracy, fmt, workers, scheduler):
    """Monte Carlo yield of SPEC's design under its [tolerances]: the fraction of builds that
    pass every stage (95 % interval), survival by stage, failures by name, the tolerances'
    Sobol' indices, each failing build as one `simulate --build` command; the event simulator
    confirms a sample."""
    from .commands.yield_ import commands_from, run_yield, write_outputs, yield_json, yield_text
    from .spec import load_spec

    if out is not None:
        out = _out_folder(out, spec, "yield")
    loaded = load_spec(spec)
    result = run_yield(loaded, spec, builds=builds, stages=stages, seed=seed, accuracy=accuracy,
                       workers=workers, scheduler=scheduler)
    if out:  # its failing builds rerun with the design saved there (simulate --from)
        result = commands_from(result, out)
    files = write_outputs(result, out) if out else []
    click.echo(yield_json(result) if fmt == "json" else
               yield_text(result, loaded.name or spec) + "".join(f"  {f}\n" for f in files),
               nl=fmt == "json")
    return EXIT_OK


@main.command()
@click.argument("source", metavar="SPEC_OR_JSON", type=str)
@click.option("--out", type=click.Path(file_okay=False, path_type=str), default=None,
              help="Folder for report.html (default: the spec's name, else the source file's, "
              "followed by -report).")
@click.option("--count", type=_Count(1, 10_000_000), default=None,
              help="Stages on the drawing (default: verification.stages).")
@click.option("--no-tolerance", is_flag=True, help="Do not solve for the tolerance.")
@click.option("--yield", "yield_path", type=click.Path(dir_okay=False, path_type=str),
              default=None, help="A yield analysis saved as JSON, shown on the page.")
@click.option("--no-yield", is_flag=True,
              help="Do not compute the yield of the spec's [tolerances] for the page.")
@_guarded
def report(source, out, count, no_tolerance, yield_path, no_yield):
    """One self-contained HTML page of a design (docs/report.md): design, margins, tolerances,
    parts, the drawing and the simulated run animated. Exit 1 (page still written) when the
    design does not work."""
    from .report.page import report_command

    out = _out_folder(out, source, "report")
    works = report_command(source, out, count, no_tolerance, click.echo, yield_path,
                           no_yield)
    return EXIT_OK if works else EXIT_FAILED


@main.command()
@click.argument("targets", nargs=-1, required=True, type=click.Path(path_type=str),
                metavar="SPEC_OR_DIR...")
@click.option("--junit", type=click.Path(dir_okay=False), default=None,
              help="Also write a JUnit XML report to this file (not one of the specs checked).")
@_guarded
def check(targets, junit):
    """CI gate: solve and verify each spec (or every *.toml in a directory) and test its
    [expect] table (a feasible design must also pass the simulator's verification, unless the
    table says verified = false). One line per spec; exit 1 if any expectation fails, 2 on bad
    input."""
    from pathlib import Path

    from .check import check_spec, junit_xml, spec_paths
    from .errors import SpecError

    if junit is not None and not junit:  # else the report the user asked for is silently lost
        raise SpecError("command line", "--junit", "a file name", "''")
    if junit is not None:
        from .io import check_output

        check_output(junit, "--junit")
    paths = spec_paths(list(targets))
    if junit and Path(junit).resolve() in {p.resolve() for p in paths}:
        raise SpecError("command line", "--junit", "a file that is not one of the specs checked",
                        junit)
    results = []
    for path in paths:
        results.append(check_spec(path))
        click.echo(results[-1].line())
    if junit:
        from .io import write_atomic

        write_atomic(junit, junit_xml(results))
    if any(r.error for r in results):
        return EXIT_BAD_INPUT
    return EXIT_OK if all(r.passed for r in results) else EXIT_FAILED


if __name__ == "__main__":  # pragma: no cover
    main()
