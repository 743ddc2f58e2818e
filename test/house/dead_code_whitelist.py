"""Names that vulture takes for dead code but that are used, each with who uses it. Read by
test/house/test_dead_code.py (vulture counts an attribute named here as used); the function
is never called."""

from irb140_dynamics.core.equations.printing import CPrinter, PythonPrinter
from irb140_dynamics.sim.engine import SimulatedArm


def used_by_name(arm: SimulatedArm):
    return (
        # SymPy's printers call _print_<class of the expression> by name.
        CPrinter._print_Float,
        CPrinter._print_Rational,
        PythonPrinter._print_Float,
        PythonPrinter._print_Rational,
        # Written for MuJoCo to read: the model's option flags (mjDSBL_AUTORESET).
        arm.mj_model.opt.disableflags,
    )
