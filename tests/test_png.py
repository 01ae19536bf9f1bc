"""The report's own PNG writer (report.png): files any reader decodes to exactly matplotlib's pixels."""
import numpy as np
import pytest
from PIL import Image

from uqflight.report import plots  # noqa: F401 (the Agg backend, as the report sets it)
from uqflight.report.png import png_bytes, write_png


def test_any_rgba_image_round_trips_through_pillow(tmp_path):
    rng = np.random.default_rng(3)
    image = rng.integers(0, 256, size=(37, 53, 4), dtype=np.uint8)  # odd sizes, every byte value
    path = tmp_path / "noise.png"
    path.write_bytes(png_bytes(image, 110, {"Software": "uqflight test"}))
    with Image.open(path) as read:
        read.load()  # Pillow checks each chunk's CRC as it reads
        assert read.mode == "RGBA" and read.size == (53, 37)
        assert np.array_equal(np.asarray(read), image)
        assert read.info["Software"] == "uqflight test"
        assert read.info["dpi"] == pytest.approx((110, 110), abs=0.01)  # pHYs holds whole pixels per metre


def test_a_figure_has_the_pixels_and_resolution_savefig_gives(tmp_path):
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(5, 2.5), dpi=72)
    t = np.linspace(0, 10, 400)
    axes[0].plot(t, np.sin(t), label="sin")
    axes[0].fill_between(t, np.sin(t) - 0.3, np.sin(t) + 0.3, alpha=0.3)
    axes[0].legend()
    axes[0].set_title("angle of attack α [deg]")
    axes[1].pcolormesh(np.outer(np.arange(20), np.arange(30)), cmap="viridis")
    fig.tight_layout()
    fig.savefig(tmp_path / "matplotlib.png", dpi=110)
    write_png(fig, tmp_path / "ours.png", 110)
    assert fig.dpi == 72  # the figure's own resolution is left as it was
    plt.close(fig)
    with Image.open(tmp_path / "matplotlib.png") as theirs, Image.open(tmp_path / "ours.png") as ours:
        assert ours.size == theirs.size == (550, 275)
        assert np.array_equal(np.asarray(ours), np.asarray(theirs))
        assert ours.info["dpi"] == theirs.info["dpi"]
        assert ours.info["Software"] == theirs.info["Software"]


@pytest.mark.parametrize("image", [np.zeros((4, 4, 3), np.uint8), np.zeros((4, 4, 4), np.float64)])
def test_anything_but_8_bit_rgba_is_refused(image):
    with pytest.raises(ValueError, match="uint8"):
        png_bytes(image, 100)
