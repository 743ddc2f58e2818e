"""The package uses rclpy through its public API only: no private attribute or method of an
rclpy object is read, written or replaced (any rclpy release may change those).

Read from the source (AST): an attribute ``x._name`` is allowed only where ``x`` is
``self``, ``cls`` or ``super()``, or where ``_name`` is a private name the package itself
defines (an attribute or method of its own classes, reached from a sibling object) and no
rclpy class has; a public function of the standard library spelled with an underscore
(``os._exit``) too.
And no attribute that rclpy's node-side classes define (their methods, the attributes
their ``__init__`` sets) is assigned on an object other than ``self``: that would replace
rclpy's behaviour from outside.
"""

import ast
import inspect
import textwrap

import rclpy.client
import rclpy.node
import rclpy.publisher
import rclpy.service
import rclpy.subscription
import rclpy.timer

from ..support.paths import ROOT

STANDARD_LIBRARY = {("os", "_exit")}  # public, documented functions with an underscore
RCLPY_CLASSES = (
    rclpy.node.Node,
    rclpy.service.Service,
    rclpy.client.Client,
    rclpy.subscription.Subscription,
    rclpy.publisher.Publisher,
    rclpy.timer.Timer,
)
# no method of an rclpy object is replaced
KNOWN_REPLACEMENTS = set()


def package_trees():
    for path in sorted((ROOT / "irb140_dynamics").rglob("*.py")):
        yield str(path.relative_to(ROOT)), ast.parse(path.read_text())


def own_private_names(trees) -> set[str]:
    """Private names the package defines: methods, functions, classes, and attributes set on self."""
    names = set()
    for _, tree in trees:
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                names.add(node.name)
            elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
                if isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"):
                    names.add(node.attr)
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                names.add(node.target.id)
    return {name for name in names if _private(name)}


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def _receiver_is_own(value: ast.expr) -> bool:
    if isinstance(value, ast.Name) and value.id in ("self", "cls"):
        return True
    return isinstance(value, ast.Call) and isinstance(value.func, ast.Name) and value.func.id == "super"


def private_accesses(trees, own: set[str]) -> list[str]:
    found = []
    for path, tree in trees:
        for node in ast.walk(tree):
            if not (isinstance(node, ast.Attribute) and _private(node.attr)) or _receiver_is_own(node.value):
                continue
            receiver = node.value.id if isinstance(node.value, ast.Name) else None
            if node.attr in own or (receiver, node.attr) in STANDARD_LIBRARY:
                continue
            found.append(f"{path}:{node.lineno}: {ast.unparse(node)}")
    return found


def rclpy_attribute_names() -> set[str]:
    """What rclpy's node-side classes define: class attributes and those their __init__ sets."""
    names = set()
    for cls in RCLPY_CLASSES:
        for klass in cls.__mro__[:-1]:
            names |= set(vars(klass))
            init = vars(klass).get("__init__")
            if init is None:
                continue
            tree = ast.parse(textwrap.dedent(inspect.getsource(init)))
            for node in ast.walk(tree):
                if isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
                    names.add(node.attr)
    return {name for name in names if not name.startswith("__")}


def replacements(trees, rclpy_names: set[str]) -> list[str]:
    found = []
    for path, tree in trees:
        for node in ast.walk(tree):
            if not (isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store)):
                continue
            if _receiver_is_own(node.value) or node.attr not in rclpy_names:
                continue
            if (path, node.attr) not in KNOWN_REPLACEMENTS:
                found.append(f"{path}:{node.lineno}: {ast.unparse(node)} = ...")
    return found


def allowed_private_names(trees) -> set[str]:
    """The package's own private names, less those rclpy's classes also have (``_parameters``):
    those only on self or cls."""
    return own_private_names(trees) - rclpy_attribute_names()


def test_no_private_attribute_of_an_rclpy_object_is_used():
    trees = list(package_trees())
    assert private_accesses(trees, allowed_private_names(trees)) == []


def test_no_attribute_of_an_rclpy_object_is_replaced():
    trees = list(package_trees())
    assert replacements(trees, rclpy_attribute_names()) == []


# the uses the package made before (parameter overrides read and written, rclpy's check of
# undeclared names replaced, its parameter services' callbacks wrapped): each one is caught
OLD_USES = """
def declare(node, spec):
    given = node._parameter_overrides.get(spec.name)
    node._parameter_overrides[spec.name] = given


class Live:
    def __init__(self, node):
        node._check_undeclared_parameters = self._refuse_undeclared
        self._node, self._parameters = node, {}  # a name of rclpy's too: on self only
        self._node._parameters.clear()

    def _refuse_undeclared(self, parameters):
        pass


def guard(node):
    for service in node.services:
        service.callback = wrapped(service.callback)
"""


def test_the_rules_catch_the_old_uses():
    trees = [("old.py", ast.parse(OLD_USES))]
    found = private_accesses(trees, allowed_private_names(trees))
    assert sorted(line.split(": ", 1)[1] for line in found) == [
        "node._check_undeclared_parameters",
        "node._parameter_overrides",
        "node._parameter_overrides",
        "self._node._parameters",
    ]
    assert sorted(line.split(": ", 1)[1] for line in replacements(trees, rclpy_attribute_names())) == [
        "node._check_undeclared_parameters = ...",
        "service.callback = ...",
    ]
