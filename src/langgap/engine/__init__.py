"""Running episodes: the run spec, the plan, one episode, the worker pools and the scheduler that drives them."""
