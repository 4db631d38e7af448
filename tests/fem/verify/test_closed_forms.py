import numpy as np

from fem.verify.closed_forms import fine_then_growing


def test_graded_grid_ends_on_the_body_only_when_asked():
    loose = fine_then_growing(0.25, 1.8, 1.5, 8.0)
    exact = fine_then_growing(0.25, 1.8, 1.5, 8.0, exact=True)
    np.testing.assert_allclose(loose[:8], np.arange(8) * 0.25)
    assert loose[-1] > 9.5                            # the first node beyond 8 mm: 9.543 mm
    assert exact[-1] == 8.0 and len(exact) == len(loose)      # its last node moved onto the face
    np.testing.assert_array_equal(exact[:-1], loose[:-1])
    cells = np.diff(exact)
    assert (cells > 0).all() and cells[-1] >= 0.5 * cells[-2]


def test_a_thin_last_cell_is_merged_into_the_one_before():
    np.testing.assert_array_equal(fine_then_growing(1.0, 2.0, 2.0, 6.5), [0, 1, 2, 4, 8])
    np.testing.assert_array_equal(fine_then_growing(1.0, 2.0, 2.0, 6.5, exact=True), [0, 1, 2, 4, 6.5])
    # 0, 1, 2, 4, 8, 16: 8-8.5 would be thinner than half of 4-8, so 8 goes and 4-8.5 is one cell
    np.testing.assert_array_equal(fine_then_growing(1.0, 2.0, 2.0, 8.5, exact=True), [0, 1, 2, 4, 8.5])
