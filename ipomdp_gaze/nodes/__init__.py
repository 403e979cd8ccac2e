"""ROS 2 nodes: thin wrappers around the model core."""
