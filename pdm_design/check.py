"""The CI gate: solve each spec, verify it, and test its [expect] table."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from .api import DesignOutcome, design
from .errors import PdmError, SpecError
from .spec import load_spec


@dataclass(frozen=True)
class CheckResult:
    """One spec's verdict. failures: one reason per expectation not met; error: bad input."""

    source: str
    failures: tuple[str, ...] = ()
    error: str | None = None
    seconds: float = 0.0

    @property
    def passed(self) -> bool:
        return not self.failures and self.error is None

    def line(self) -> str:
        if self.error:
            text = f"ERROR {self.source}: {self.error}"
        elif self.failures:
            text = f"FAIL  {self.source}: {'; '.join(self.failures)}"
        else:
            text = f"PASS  {self.source}"
        return printable(text)


# control characters, lone surrogates (undecodable file names) and the two non-characters:
# none may stand in XML 1.0, and a raw newline would split a spec's one line in two
_UNPRINTABLE = re.compile("[\x00-\x1f\x7f\ud800-\udfff\ufffe\uffff]")


def printable(text: str) -> str:
    """text with every character of _UNPRINTABLE written as a \\uXXXX escape."""
    return _UNPRINTABLE.sub(lambda m: f"\\u{ord(m.group()):04x}", text)


def spec_paths(targets: list[str]) -> list[Path]:
    """The spec files named, with each directory expanded to its *.toml files (sorted). A
    directory without any is bad input: a CI gate that checks nothing must not pass."""
    paths: list[Path] = []
    for target in targets:
        path = Path(target)
        if path.is_dir():
            found = sorted(path.glob("*.toml"))
            if not found:
                raise SpecError(target, "", "a spec file or a folder with *.toml files",
                                "no *.toml files")
            paths.extend(found)
        else:
            paths.append(path)
    return paths


def check_spec(path: Path) -> CheckResult:
    """One spec's verdict. Any error, even an internal one, becomes this spec's ERROR result,
    so that the other specs are still checked and the JUnit report still written."""
    import os
    import time

    start = time.perf_counter()
    try:
        failures = tuple(unmet_expectations(design(load_spec(path))))
    except SpecError as error:
        # The ERROR line already names the file: drop the message's own "FILE: " prefix.
        text, prefix = str(error), f"{error.file}: "
        same_file = error.file == str(path) and text.startswith(prefix)
        message = text[len(prefix):] if same_file else text
    except PdmError as error:
        message = str(error)
    except Exception as error:
        if os.environ.get("PDM_DESIGN_DEBUG"):  # the CLI's switch for seeing the traceback
            raise
        message = f"internal error ({type(error).__name__}): {error}"
    else:
        return CheckResult(str(path), failures=failures, seconds=time.perf_counter() - start)
    return CheckResult(str(path), error=message, seconds=time.perf_counter() - start)


def unmet_expectations(outcome: DesignOutcome) -> list[str]:
    """Each expectation of the spec that the outcome does not meet, in words."""
    expect, out = outcome.spec.expect, []
    feasible = outcome.status.is_success
    if expect.feasible is not None and feasible != expect.feasible:
        why = f" ({outcome.violations[0]})" if outcome.violations else ""
        out.append(f"expected {'feasible' if expect.feasible else 'infeasible'}, "
                   f"got {outcome.status.value}{why}")
    verification = outcome.verification or {}
    verified = bool(verification.get("passed"))
    if expect.verified is not None and verified != expect.verified:
        out.append(f"expected verified = {expect.verified}, got {verified}"
                   + (f" ({verification.get('summary')})" if verification else
                      " (not verified)"))
    elif expect.verified is None and feasible and verification and not verified:
        # a design the simulator refutes does not work, whatever the closed forms say: a gate
        # that passed it would miss exactly the regressions verification exists to catch
        out.append(f"the simulator refutes the design ({verification.get('summary')}); "
                   "[expect] verified = false accepts that")
    if expect.min_objective is not None:
        value = (outcome.objective or {}).get("value")
        if value is None:
            out.append(f"expected an objective of at least {expect.min_objective:g}, got none "
                       f"({_why_none(outcome, 'objective')})")
        elif value < expect.min_objective:
            out.append(f"objective {_show(value)} is below the expected minimum "
                       f"{expect.min_objective:g}")
    if expect.min_tolerance is not None:
        smallest = _smallest_side(outcome.tolerance)
        if smallest is None:
            out.append(f"expected a tolerance of at least {expect.min_tolerance:g} m, got none "
                       f"({_why_none(outcome, 'tolerance')})")
        elif smallest < expect.min_tolerance:
            out.append(f"tolerance {_show(smallest)} m is below the expected minimum "
                       f"{expect.min_tolerance:g} m")
    if expect.min_margin is not None:
        margins = outcome.analysis.margins
        name = min(margins, key=margins.get) if margins else None
        if name is None or margins[name] < expect.min_margin:
            out.append(f"smallest margin {name} = {_show(margins.get(name))} is below the "
                       f"expected minimum {expect.min_margin:g}")
    if expect.min_yield is not None:
        from .commands.yield_ import unmet_min_yield

        out += unmet_min_yield(outcome)
    return out


def _why_none(outcome, what: str) -> str:
    """Why a design has no objective value or tolerance, in words."""
    if not outcome.spec.free_variables:
        return f"a fixed design is evaluated, not optimised: it has no {what}"
    if what == "tolerance" and not outcome.spec.objective.get("max_offset_tolerance"):
        return "the spec does not ask for max_offset_tolerance"
    return f"status {outcome.status.value}"


def _smallest_side(tolerance: dict | None) -> float | None:
    """Smallest half-width of the tolerance box (m), over its numeric sides."""
    if not tolerance:
        return None
    sides = [v for k, v in tolerance.items() if isinstance(v, (int, float)) and k != "volume"]
    return min(sides) if sides else None


def _show(value) -> str:
    return "none" if value is None else f"{value:.4g}"


def junit_xml(results: list[CheckResult]) -> str:
    """A JUnit XML report: one test case per spec."""
    import xml.etree.ElementTree as ET

    suite = ET.Element("testsuite", name="pdm-design check", tests=str(len(results)),
                       failures=str(sum(bool(r.failures) for r in results)),
                       errors=str(sum(r.error is not None for r in results)))
    for result in results:
        case = ET.SubElement(suite, "testcase", classname="pdm-design.check",
                             name=printable(result.source), time=f"{result.seconds:.3f}")
        if result.error:
            ET.SubElement(case, "error", message=printable(result.error))
        for failure in result.failures:
            ET.SubElement(case, "failure", message=printable(failure))
    return ET.tostring(suite, encoding="unicode", xml_declaration=True) + "\n"
