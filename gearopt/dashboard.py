"""optuna-dashboard on a gearopt study, with a "Best Trials" card that holds feasible trials only.

optuna-dashboard (0.21) reads each trial's constraint values from the list gearopt stores
(:mod:`gearopt.best`): its trial table lists them and its Pareto plot draws the feasible front.
Its study API's ``best_trials`` (the "Best Trials" card) is computed upstream over every COMPLETE
trial, constraints aside (``_app.py``, ``get_study_detail``), so an infeasible gear set can be
offered as a best one. No stored data changes that; the least intrusive remedy short of an
upstream change is :class:`FeasibleBestTrials`, a WSGI filter around the dashboard's own app
that answers the study API with ``best_trials`` recomputed from the same response's trials: the
feasible ones (every constraint value <= 0) that no other feasible trial dominates, or, for one
objective, the best feasible one. Everything else passes through unchanged.

``gearopt dashboard STUDY.toml`` serves that app (optional dependency ``optuna-dashboard``,
the ``dashboard`` extra) on an existing study; it never creates a database or a study.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Iterable, Sequence
from typing import Any
from urllib.parse import parse_qs, urlencode

import optuna

from gearopt.errors import StudyError
from gearopt.storage import default_storage_url, masked_url, study_exists
from gearopt.studyfile import StudySpec

__all__ = ["FeasibleBestTrials", "dashboard_app", "feasible_best", "serve"]

#: the study detail endpoint of optuna-dashboard's API
DETAIL_PATH = re.compile(r"^/api/studies/(\d+)/?$")


def _feasible(trial: dict[str, Any]) -> bool:
    return trial.get("state") == "Complete" and all(
        c <= 0.0 for c in trial.get("constraints") or []
    )


def _signed(trial: dict[str, Any], directions: Sequence[str]) -> list[float]:
    """The trial's values, each to be minimised."""
    return [v if d == "minimize" else -v for v, d in zip(trial["values"], directions, strict=True)]


def feasible_best(trials: Iterable[dict[str, Any]], directions: Sequence[str]) -> list[dict]:
    """The best trials among the feasible COMPLETE ones, as the dashboard serialises trials.

    Parameters
    ----------
    trials
        Serialised trials (``state``, ``values``, ``constraints`` as optuna-dashboard's API
        gives them).
    directions
        ``"minimize"`` / ``"maximize"`` per objective.

    Returns
    -------
    list of dict
        Several objectives: the feasible trials no other feasible trial dominates, in trial
        order; one objective: the first feasible trial with the best value (empty if none).
    """
    candidates = [t for t in trials if _feasible(t) and t.get("values") is not None]
    signed = [_signed(t, directions) for t in candidates]
    if len(directions) == 1:
        if not candidates:
            return []
        best = min(range(len(candidates)), key=lambda i: signed[i][0])
        return [candidates[best]]

    def dominated(i: int) -> bool:
        return any(
            all(a <= b for a, b in zip(other, signed[i], strict=True)) and other != signed[i]
            for other in signed
        )

    return [t for i, t in enumerate(candidates) if not dominated(i)]


class FeasibleBestTrials:
    """A WSGI filter around optuna-dashboard's app: the study API's ``best_trials`` feasible.

    Parameters
    ----------
    app
        optuna-dashboard's WSGI application (``optuna_dashboard.wsgi(storage)``).
    """

    def __init__(self, app: Callable) -> None:
        self.app = app

    def _call(self, environ: dict, query: str) -> tuple[str, list, bytes]:
        inner = dict(environ, QUERY_STRING=query)
        started: list = []

        def start_response(status, headers, exc_info=None):
            started[:] = [status, headers]
            return lambda data: None

        body = b"".join(self.app(inner, start_response))
        return started[0], started[1], body

    def __call__(self, environ: dict, start_response: Callable) -> Iterable[bytes]:
        match = DETAIL_PATH.match(environ.get("PATH_INFO", ""))
        if environ.get("REQUEST_METHOD", "GET") != "GET" or match is None:
            return self.app(environ, start_response)
        query = parse_qs(environ.get("QUERY_STRING", ""))
        after = query.pop("after", ["0"])[0]
        # the whole trial list (the front needs every trial), then the page asked for
        status, headers, body = self._call(environ, urlencode(query, doseq=True))
        if not status.startswith("200"):
            start_response(status, headers)
            return [body]
        detail = json.loads(body)
        if not detail.get("is_preferential"):
            detail["best_trials"] = feasible_best(detail["trials"], detail["directions"])
        if after.isdigit():
            detail["trials"] = detail["trials"][int(after) :]
        out = json.dumps(detail).encode()
        headers = [(k, v) for k, v in headers if k.lower() != "content-length"]
        start_response(status, [*headers, ("Content-Length", str(len(out)))])
        return [out]


def _dashboard():
    try:
        import optuna_dashboard
    except ImportError:
        raise StudyError(
            "dashboard",
            "optuna-dashboard",
            "is not installed: pip install 'gearopt[dashboard]'",
        ) from None
    return optuna_dashboard


def dashboard_app(spec: StudySpec, storage: str | None = None) -> FeasibleBestTrials:
    """optuna-dashboard's app on the study's storage, its best trials feasible.

    Raises
    ------
    StudyError
        The storage holds no study of that name (nothing is created), or optuna-dashboard is
        not installed.
    """
    url = storage or default_storage_url(spec)
    if not study_exists(spec, url):
        raise StudyError(
            "study", spec.name, f"is not in {masked_url(url)}: run it first (gearopt study run)"
        )
    dashboard = _dashboard()
    rdb = optuna.storages.RDBStorage(url, skip_table_creation=True)
    return FeasibleBestTrials(dashboard.wsgi(rdb))


def serve(app: Callable, host: str, port: int) -> None:
    """Serve ``app`` with the standard library's WSGI server until interrupted."""
    from wsgiref.simple_server import make_server

    with make_server(host, port, app) as server:
        print(f"gearopt dashboard on http://{host}:{server.server_port}/ (Ctrl-C to stop)")
        try:
            server.serve_forever()
        except KeyboardInterrupt:
            pass
