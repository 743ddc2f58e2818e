"""``python -m irb140_dynamics.nodes.sim_node``: the node, as its console script starts it."""

if __name__ == "__main__":
    from irb140_dynamics.nodes.sim_node import main

    main()
