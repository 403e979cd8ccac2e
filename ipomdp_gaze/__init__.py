"""I-POMDP infomax model of eye movement: the numpy model core (no rclpy)."""
