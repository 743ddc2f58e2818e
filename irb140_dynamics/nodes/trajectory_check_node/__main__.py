"""python -m irb140_dynamics.nodes.trajectory_check_node"""

from irb140_dynamics.nodes.trajectory_check_node import main

main()
