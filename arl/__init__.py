"""arl: adversarial reinforcement learning of the robot policy on game DAGs."""
