"""`small-vla`: a small vision-language behaviour-cloning policy that sees what a VLA sees (cameras, 8-D state,
the instruction), trained here by `langgap train small-vla`."""
