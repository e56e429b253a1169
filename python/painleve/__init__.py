"""painleve: the Painlevé arm of Marchese, Coraggio, Hogan and di Bernardo,
"Control of Painlevé Paradox in a Robotic System" (ECC 2019), in Python.

A two-link arm presses its tip on a moving belt; with Coulomb friction some
configurations make the contact problem inconsistent (the Painlevé paradox).
This package calls the workspace's Rust libraries (the hybrid plant simulator,
the SIL rig with the firmware linked in, and the analyses) in this process, with
the arguments, defaults, validation and summaries of the ``sil-host`` command
line, and returns NumPy arrays:

- :func:`simulate`: one open-loop run;
- :func:`admissible`: paper Table II;
- :func:`modes`: paper Fig. 2;
- :func:`sweep`: paper Figs. 3 and 9;
- :func:`poincare`: paper Fig. 4;
- :func:`zmax`: ``Z_t,sliding`` (experiments 5 and 6);
- :func:`run`: a closed-loop SIL run of a scenario;
- :func:`sensitivity`: the results under each open modelling choice;
- :func:`replay`: a recorded run's frames through the firmware, compared bit for bit;
- :func:`load`: any output folder the CLI writes;
- the arm's :class:`Model` (kinematics, ``J``, ``M``, ``Q``, ``p``, ``b``);
- objects to hold and step: :class:`Scenario`, :class:`Plant`,
  :class:`Firmware`, and :func:`run_controller` (a Python controller in the
  closed loop).

Every function returns a :class:`Result`: ``summary`` (the command's
``summary.json`` as a dict), ``tables`` (``{name: Table}``, a :class:`Table`
being ``{column: numpy array}``, named as the CLI's CSV files), ``validity``
(the model-violation counters) and ``failure``. Bad input raises
:class:`PainleveError` (a ``ValueError``) with the CLI's message; Ctrl-C stops a
long call cleanly and raises ``KeyboardInterrupt``. See docs/python.md.
"""

from ._painleve import PainleveError, __version__
from ._api import (
    admissible,
    default_scenario,
    modes,
    poincare,
    replay,
    run,
    scenario_toml,
    sensitivity,
    simulate,
    sweep,
    zmax,
)
from ._load import load, read_arrow, read_csv, read_mcap
from ._objects import Command, Firmware, Model, Plant, Scenario, Sensed, Step, run_controller
from ._result import PainleveWarning, Result, Table, describe_violations

__all__ = [
    "Command",
    "Firmware",
    "PainleveError",
    "PainleveWarning",
    "Model",
    "Plant",
    "Result",
    "Scenario",
    "Sensed",
    "Step",
    "Table",
    "__version__",
    "admissible",
    "default_scenario",
    "describe_violations",
    "load",
    "modes",
    "poincare",
    "read_arrow",
    "read_mcap",
    "read_csv",
    "replay",
    "run",
    "run_controller",
    "scenario_toml",
    "sensitivity",
    "simulate",
    "sweep",
    "zmax",
]
