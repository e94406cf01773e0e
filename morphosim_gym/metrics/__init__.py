"""Image metrics shared by the report commands, the benchmarks and the tests."""

from .image import delta_e, iou, mean_lab, psnr, rgb_to_lab, ssim

__all__ = ["delta_e", "iou", "mean_lab", "psnr", "rgb_to_lab", "ssim"]
