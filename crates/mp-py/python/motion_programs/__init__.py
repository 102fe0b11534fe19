"""Human motion as programs.

Keypoints from video (BlazePose, MoveNet), concrete programs (per-joint
primitives over shared segments), abstract programs (loops of probabilistic
primitives), repetition counts, motion grammars — the same library functions
and defaults as the ``mp`` command line tool.

>>> import motion_programs as mp
>>> track = mp.extract("squats.mp4")            # doctest: +SKIP
>>> program = mp.fit(track)                      # doctest: +SKIP
>>> mp.count(track).total                        # doctest: +SKIP
>>> people = mp.extract("gym.mp4", people=True)  # doctest: +SKIP
>>> [(p.id, p.frames_found) for p in people]     # doctest: +SKIP
"""

from ._native import (  # noqa: F401
    AbstractError,
    AbstractProgram,
    Analyser,
    CancelledError,
    Counts,
    ForecastError,
    GrammarError,
    MpError,
    OutputError,
    ParamError,
    People,
    Person,
    PoseError,
    Program,
    ProgramError,
    Summary,
    Track,
    TrackError,
    __version__,
    batch,
    count,
    default_params,
    extract,
    fit,
    grammar_learn,
    grammar_symbols,
    live,
    Live,
    predict,
    read_people,
    read_track,
    refine,
    RefineError,
    run,
)
from ._native import abstract as abstract_program  # noqa: F401

# `abstract` is the name used in the documentation; it is also a valid
# identifier in Python (not a keyword).
abstract = abstract_program

__all__ = [
    "AbstractError",
    "AbstractProgram",
    "Analyser",
    "CancelledError",
    "Counts",
    "ForecastError",
    "GrammarError",
    "MpError",
    "OutputError",
    "ParamError",
    "People",
    "Person",
    "PoseError",
    "Program",
    "ProgramError",
    "Summary",
    "Track",
    "TrackError",
    "abstract",
    "batch",
    "count",
    "default_params",
    "extract",
    "fit",
    "grammar_learn",
    "grammar_symbols",
    "live",
    "Live",
    "predict",
    "read_people",
    "read_track",
    "refine",
    "RefineError",
    "run",
]
