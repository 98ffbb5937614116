"""Training: the `small-bc` trainer (CPU, PyTorch) and the paper's LeRobot fine-tuning experiments."""
