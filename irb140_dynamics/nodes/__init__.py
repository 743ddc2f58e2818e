"""The ROS 2 nodes, one room each (``nodes/<name>/``): ``node.py`` (the Node and its
main(): messages in, calls to the core, messages out) and, where it has them, the node's
settings and helpers of its own. May import ``ros``, ``core``, ``identification``, ``sim``;
never another node (what several nodes share goes to ``ros``), never ``tools``.
"""
