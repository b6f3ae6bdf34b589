"""train --init FILE --size N: the learned position tables follow the new
input side (stretch_position_tables)."""

import unittest

import torch

from aprt_tools.model.apr_transformer import AprConfig, AprTransformer
from aprt_tools.train import stretch_position_tables

ROW, COL = "backbone.1.row_embed.weight", "backbone.1.col_embed.weight"


def tables(cells=50, width=4):
    # Row i holds i in every column: a resampled row reads as its source position.
    ramp = torch.arange(cells, dtype=torch.float32).unsqueeze(1).repeat(1, width)
    return {ROW: ramp.clone(), COL: ramp.clone() * 2, "other": torch.ones(3)}


class StretchPositionTables(unittest.TestCase):
    def test_64_to_96_samples_cell_centres(self):
        state = tables()
        out = stretch_position_tables(state, 64, 96)
        # New row k of 12 reads old (k + 0.5) * 64 / 96 - 0.5, clamped to old rows 0..7.
        want = ((torch.arange(12) + 0.5) * 64 / 96 - 0.5).clamp(0, 7)
        self.assertTrue(torch.allclose(out[ROW][:12, 0], want, atol=1e-6))
        self.assertTrue(torch.allclose(out[COL][:12, 0], 2 * want, atol=1e-6))
        # The coarser map (4 -> 6 cells) scales by the same 1.5 and wants the
        # same positions, except at its edge: its last row reads 3.17, a sixth
        # of old row 4 (which only the finer map used) beside old row 3.
        self.assertAlmostEqual(float(out[ROW][5, 0]), 5.5 * 4 / 6 - 0.5, places=5)
        # Rows beyond the finer map's reach, and other weights, are untouched;
        # the input state is not modified.
        self.assertTrue(torch.equal(out[ROW][12:], state[ROW][12:]))
        self.assertIs(out["other"], state["other"])
        self.assertTrue(torch.equal(state[ROW], tables()[ROW]))

    def test_same_side_is_identity_and_too_large_is_refused(self):
        state = tables()
        out = stretch_position_tables(state, 64, 64)
        self.assertTrue(torch.equal(out[ROW], state[ROW]))
        with self.assertRaisesRegex(ValueError, "needs 52 position cells, the tables have 50"):
            stretch_position_tables(state, 64, 416)

    def test_loads_into_the_larger_network(self):
        cfg = AprConfig.named("full", 64)
        cfg.hidden_dim, cfg.dim_feedforward, cfg.enc_layers, cfg.dec_layers = 32, 64, 1, 1
        state = AprTransformer(cfg).state_dict()
        cfg.image_size = 96
        big = AprTransformer(cfg)
        big.load_state_dict(stretch_position_tables(state, 64, 96))
        big.eval()
        with torch.no_grad():
            y = big(torch.zeros(1, 3, 96, 96))
        self.assertTrue(all(torch.isfinite(v).all() for v in
                            (y.values() if isinstance(y, dict) else [y])))


if __name__ == "__main__":
    unittest.main()
