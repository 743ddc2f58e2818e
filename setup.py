from glob import glob

from setuptools import find_packages, setup

package_name = "irb140_dynamics"

# The executables colcon installs (`setup.py develop`/`install`) as light scripts: the
# program's function imported and called, as pip's wheels make them. setuptools' own
# easy-install script first imports importlib.metadata and scans every installed
# distribution (0.1 to 0.2 s), before the executable's entry (irb140_dynamics.entry) can
# note a Ctrl-C: one then was a traceback.
LIGHT_SCRIPT = """# -*- coding: utf-8 -*-
import sys

from {module} import {function}

if __name__ == "__main__":
    sys.exit({function}())
"""


def _light_scripts(cls, dist, header=None):
    header = cls.get_header() if header is None else header
    for kind in ("console", "gui"):
        for name, entry_point in dist.get_entry_map(f"{kind}_scripts").items():
            cls._ensure_safe_name(name)
            text = LIGHT_SCRIPT.format(module=entry_point.module_name, function=entry_point.attrs[0])
            yield from cls._get_script_args(kind, name, header, text)


try:  # setuptools without easy_install (pip's wheels): its scripts are light already
    from setuptools.command.easy_install import ScriptWriter

    ScriptWriter.get_args = classmethod(_light_scripts)
except ImportError:
    pass

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test", "test.*", "bench", "bench.*"]),
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{package_name}"]),
        (f"share/{package_name}", ["package.xml"]),
        (f"share/{package_name}/config", glob("config/*.yaml")),
        (f"share/{package_name}/urdf", glob("urdf/*.urdf")),
        (f"share/{package_name}/launch", glob("launch/*.launch.py")),
        (f"share/{package_name}/rviz", glob("rviz/*.rviz")),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="irb140_dynamics developers",
    maintainer_email="irb140-dynamics@example.com",
    description="Live inverse dynamics, gravity compensation and payload checks for the ABB IRB-140",
    license="Apache-2.0",
    tests_require=["pytest"],
    entry_points={
        "console_scripts": [
            "id_node = irb140_dynamics.programs:id_node",
            "payload_check_node = irb140_dynamics.programs:payload_check_node",
            "demo_node = irb140_dynamics.programs:demo_node",
            "sim_node = irb140_dynamics.programs:sim_node",
            "export_urdf = irb140_dynamics.programs:export_urdf",
            "identify = irb140_dynamics.programs:identify",
            "excitation = irb140_dynamics.programs:excitation",
            "record = irb140_dynamics.programs:record",
            "equations = irb140_dynamics.programs:equations",
            "retime = irb140_dynamics.programs:retime",
            "load_diagram = irb140_dynamics.programs:load_diagram",
            "calibrate_collision = irb140_dynamics.programs:calibrate_collision",
            "trajectory_check_node = irb140_dynamics.programs:trajectory_check_node",
            # the tools under names of their own, for an install without the ros2 CLI (pip)
            "irb140-export-urdf = irb140_dynamics.programs:export_urdf",
            "irb140-identify = irb140_dynamics.programs:identify",
            "irb140-excitation = irb140_dynamics.programs:excitation",
            "irb140-record = irb140_dynamics.programs:record",
            "irb140-equations = irb140_dynamics.programs:equations",
            "irb140-retime = irb140_dynamics.programs:retime",
            "irb140-load-diagram = irb140_dynamics.programs:load_diagram",
            "irb140-calibrate-collision = irb140_dynamics.programs:calibrate_collision",
        ],
    },
)
