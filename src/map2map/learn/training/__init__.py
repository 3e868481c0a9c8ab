"""What both models' training shares: settings, resident data, the eq. 3.2 step, the loop
(DDP, exact resume, logs, figures) and safetensors checkpoints (the loop once)."""
