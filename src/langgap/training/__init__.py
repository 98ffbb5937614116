"""Training: the `small-bc` and `small-vla` trainers (PyTorch) and the paper's LeRobot fine-tuning experiments."""

LOSSES = ("l1", "mse")  # the regression losses on the action chunk (`TrainConfig.loss`)
