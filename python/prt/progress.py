"""Progress of long work (tracing, projection, compression, ground truth).

Every long call takes progress=: None (the C++ bars on stderr), False
(silent), "tqdm" (bars a notebook shows), or a callable that receives one
dict per update: label, unit, done, total, rate, elapsed, eta, final.
Ctrl-C stops the work at its next update and raises KeyboardInterrupt.
"""
import contextlib
import sys

from . import _prt


class ProgressPrinter:
    """A callable that prints one line per finished bar (for logs and tests)."""

    def __init__(self, stream=None):
        self.stream = stream or sys.stdout
        self.reports = []

    def __call__(self, report):
        self.reports.append(report)
        if report["final"]:
            print(f"{report['label']}: {report['done']:.0f}/{report['total']:.0f} "
                  f"in {report['elapsed']:.1f} s", file=self.stream)


def tqdm_progress():
    """A callable drawing each progress bar with tqdm (tqdm.auto: widgets in
    a notebook, text in a terminal)."""
    from tqdm.auto import tqdm
    bars = {}

    def update(report):
        bar = bars.get(report["label"])
        if bar is None:
            bar = bars[report["label"]] = tqdm(total=report["total"], desc=report["label"],
                                               leave=True)
        bar.n = report["done"]
        bar.refresh()
        if report["final"]:
            bar.close()
            del bars[report["label"]]

    return update


@contextlib.contextmanager
def progress_to(progress):
    """Routes progress for one call; yields whether the call is quiet."""
    # False: calls that take `quiet` make no bars; the others (compressors
    # that report their iterations) report to a callback that drops them.
    callback = (lambda report: None) if progress is False else \
        tqdm_progress() if progress == "tqdm" else progress
    if callback is not None and not callable(callback):
        raise TypeError("progress must be None, False, \"tqdm\" or a callable")
    previous = _prt.progress_callback()  # a call inside another's (e.g. from a plug-in)
    _prt.set_progress_callback(callback)
    try:
        yield progress is False
    finally:
        _prt.set_progress_callback(previous)
