"""Training: the `small-bc` policy (CPU, PyTorch) and the paper's LeRobot fine-tuning experiments."""
