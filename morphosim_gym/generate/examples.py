"""The generator's example prompts: the scenes of the MorphoSim paper's figures with the edit each
caption applies, plus a few robot-scene prompts. Benchmarks, examples and reports share them."""

from __future__ import annotations

__all__ = ["PAPER_SCENES", "EXAMPLE_PROMPTS"]

# (prompt, edit) pairs from the captions of the paper's figures
PAPER_SCENES: tuple[tuple[str, str], ...] = (
    ("The fish swims through the crystal-clear waters from right to left", "Make the color of the fish and seaweed black."),
    ("The bus is moving from right to left", "Make the bus yellow."),
    ("A serene boat glides gracefully through tranquil waters from left to right", "Extract the boat."),
    ("A car is moving from right to left through a serene sunlit landscape", "Extract the car."),
    ("A small, vibrant red rubber ball is bouncing from right to left", "Delete the ball."),
    ("A sleek black motorcycle is gliding effortlessly from right to left", "Delete the motorcycle."),
    ("a red cube moves to the plate while the camera circles the table", "make the cube blue and reverse its motion"),
)

# the paper's prompts first, then scenes closer to robot learning
EXAMPLE_PROMPTS: tuple[str, ...] = tuple(p for p, _ in PAPER_SCENES) + (
    "two sheep walk across the field from left to right",
    "a blue mug slides slowly across the table from left to right",
)
