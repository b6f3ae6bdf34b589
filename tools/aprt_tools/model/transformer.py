"""The DETR transformer as MS-Transformer / APR-Transformer use it.

Pre-LayerNorm encoder and decoder layers, GELU (erf form) feed-forward, final
LayerNorm on both stacks, positions added to queries and keys but never to
values. Module names match upstream so checkpoints load with strict=True.
Dropout is omitted: it has no parameters and the reference only infers and
trains small synthetic models (see tools/aprt_tools/train.py for the rate used).
"""

from __future__ import annotations

import copy

import torch
from torch import nn
from torch.nn import functional as F


class EncoderLayer(nn.Module):
    def __init__(self, d_model: int, nhead: int, dim_ff: int, dropout: float = 0.0):
        super().__init__()
        self.self_attn = nn.MultiheadAttention(d_model, nhead, dropout=dropout)
        self.linear1 = nn.Linear(d_model, dim_ff)
        self.linear2 = nn.Linear(dim_ff, d_model)
        self.norm1 = nn.LayerNorm(d_model)
        self.norm2 = nn.LayerNorm(d_model)
        self.drop = nn.Dropout(dropout)

    def forward(self, src: torch.Tensor, pos: torch.Tensor) -> torch.Tensor:
        x = self.norm1(src)
        q = k = x + pos
        src = src + self.drop(self.self_attn(q, k, value=x)[0])
        x = self.norm2(src)
        src = src + self.drop(self.linear2(self.drop(F.gelu(self.linear1(x)))))
        return src


class DecoderLayer(nn.Module):
    def __init__(self, d_model: int, nhead: int, dim_ff: int, dropout: float = 0.0):
        super().__init__()
        self.self_attn = nn.MultiheadAttention(d_model, nhead, dropout=dropout)
        self.multihead_attn = nn.MultiheadAttention(d_model, nhead, dropout=dropout)
        self.linear1 = nn.Linear(d_model, dim_ff)
        self.linear2 = nn.Linear(dim_ff, d_model)
        self.norm1 = nn.LayerNorm(d_model)
        self.norm2 = nn.LayerNorm(d_model)
        self.norm3 = nn.LayerNorm(d_model)
        self.drop = nn.Dropout(dropout)

    def forward(self, tgt, memory, pos, query_pos):
        x = self.norm1(tgt)
        q = k = x + query_pos
        tgt = tgt + self.drop(self.self_attn(q, k, value=x)[0])
        x = self.norm2(tgt)
        tgt = tgt + self.drop(self.multihead_attn(query=x + query_pos, key=memory + pos,
                                                  value=memory)[0])
        x = self.norm3(tgt)
        tgt = tgt + self.drop(self.linear2(self.drop(F.gelu(self.linear1(x)))))
        return tgt


class Encoder(nn.Module):
    def __init__(self, layer: EncoderLayer, num_layers: int, d_model: int):
        super().__init__()
        self.layers = nn.ModuleList([copy.deepcopy(layer) for _ in range(num_layers)])
        self.norm = nn.LayerNorm(d_model)

    def forward(self, src, pos):
        for layer in self.layers:
            src = layer(src, pos)
        return self.norm(src)


class Decoder(nn.Module):
    def __init__(self, layer: DecoderLayer, num_layers: int, d_model: int):
        super().__init__()
        self.layers = nn.ModuleList([copy.deepcopy(layer) for _ in range(num_layers)])
        self.norm = nn.LayerNorm(d_model)

    def forward(self, tgt, memory, pos, query_pos):
        for layer in self.layers:
            tgt = layer(tgt, memory, pos, query_pos)
        return self.norm(tgt)


class Transformer(nn.Module):
    """Encoder over the feature-map tokens, decoder over the learned queries."""

    def __init__(self, d_model: int = 256, nhead: int = 8, num_encoder_layers: int = 6,
                 num_decoder_layers: int = 6, dim_feedforward: int = 256, dropout: float = 0.0):
        super().__init__()
        if d_model % nhead:
            raise ValueError(f"d_model {d_model} is not divisible by {nhead} heads")
        self.encoder = Encoder(EncoderLayer(d_model, nhead, dim_feedforward, dropout),
                               num_encoder_layers, d_model)
        self.decoder = Decoder(DecoderLayer(d_model, nhead, dim_feedforward, dropout),
                               num_decoder_layers, d_model)
        self.d_model, self.nhead = d_model, nhead
        for p in self.parameters():  # DETR initialisation
            if p.dim() > 1:
                nn.init.xavier_uniform_(p)

    def forward(self, src: torch.Tensor, pos: torch.Tensor, query: torch.Tensor) -> torch.Tensor:
        """src, pos: (N, C, H, W); query: (Q, C). Returns (N, Q, C)."""
        n = src.shape[0]
        src = src.flatten(2).permute(2, 0, 1)
        pos = pos.flatten(2).permute(2, 0, 1)
        query_pos = query.unsqueeze(1).repeat(1, n, 1)
        tgt = torch.zeros_like(query_pos)
        memory = self.encoder(src, pos)
        hs = self.decoder(tgt, memory, pos, query_pos)
        return hs.transpose(0, 1)
