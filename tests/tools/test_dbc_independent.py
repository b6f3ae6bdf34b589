"""config/aprt_pose.dbc read by an independent DBC parser -- canmatrix
(Debian's python3-canmatrix) -- has the signals aprt's encoder writes, and
decodes the encoder's frames (written by the can_tests fixture) back to the
values that went in; the E2E CRC is recomputed here from its definition."""

import json
import logging
import os
import unittest

DBC = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "config",
                   "aprt_pose.dbc")
FRAMES = os.environ.get("APRT_CAN_FRAMES")

EXPECTED = {  # message: (id, bytes, FD, {signal: (start, length, signed, factor)})
    "APRT_Status": (0x300, 8, False, {
        "E2E_CRC": (0, 8, False, 1), "E2E_Counter": (8, 4, False, 1), "State": (12, 4, False, 1),
        "Flags": (16, 16, False, 1), "Valid": (32, 1, False, 1), "SigmaPos": (40, 16, False, 0.01),
        "SigmaYaw": (56, 8, False, 0.1)}),
    "APRT_PosXY": (0x301, 8, False, {
        "E2E_CRC": (0, 8, False, 1), "E2E_Counter": (8, 4, False, 1),
        "PosX": (16, 24, True, 0.01), "PosY": (40, 24, True, 0.01)}),
    "APRT_PosZQw": (0x302, 8, False, {
        "E2E_CRC": (0, 8, False, 1), "E2E_Counter": (8, 4, False, 1),
        "PosZ": (16, 16, True, 0.01), "QuatW": (32, 16, True, 1 / 32767),
        "QuatX": (48, 16, True, 1 / 32767)}),
    "APRT_QuatYZ": (0x303, 8, False, {
        "E2E_CRC": (0, 8, False, 1), "E2E_Counter": (8, 4, False, 1),
        "QuatY": (16, 16, True, 1 / 32767), "QuatZ": (32, 16, True, 1 / 32767)}),
    "APRT_Time": (0x304, 8, False, {
        "E2E_CRC": (0, 8, False, 1), "E2E_Counter": (8, 4, False, 1),
        "TimestampUs": (16, 48, False, 1)}),
    "APRT_PoseFD": (0x310, 48, True, {
        "E2E_CRC": (0, 8, False, 1), "E2E_Counter": (8, 4, False, 1), "State": (12, 4, False, 1),
        "Flags": (16, 16, False, 1), "Valid": (32, 1, False, 1), "PosX": (40, 32, True, 0.001),
        "PosY": (72, 32, True, 0.001), "PosZ": (104, 32, True, 0.001),
        "QuatW": (136, 16, True, 1 / 32767), "QuatX": (152, 16, True, 1 / 32767),
        "QuatY": (168, 16, True, 1 / 32767), "QuatZ": (184, 16, True, 1 / 32767),
        "SigmaPos": (200, 16, False, 0.01), "SigmaYaw": (216, 8, False, 0.1),
        "TimestampUs": (224, 64, False, 1)}),
}


def crc8_j1850(data_id, payload):
    crc = 0xFF
    for byte in [data_id & 0xFF, data_id >> 8] + list(payload[1:]):
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


def load():
    logging.disable(logging.WARNING)  # canmatrix warns about formats it has no module for
    import canmatrix.formats
    return canmatrix.formats.loadp_flat(DBC)


class DbcIndependent(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.db = load()

    def test_crc_check_value(self):
        # AUTOSAR CRC-8 SAE J1850 check value: "123456789" -> 0x4B.
        self.assertEqual(crc8_j1850(ord("1") | ord("2") << 8, b"\0" + b"3456789"), 0x4B)

    def test_messages_and_signals(self):
        self.assertEqual(sorted(f.name for f in self.db.frames), sorted(EXPECTED))
        for name, (ident, size, fd, signals) in EXPECTED.items():
            f = self.db.frame_by_name(name)
            self.assertEqual(f.arbitration_id.id, ident, name)
            self.assertEqual(f.size, size, name)
            self.assertEqual(bool(f.is_fd), fd, name)
            self.assertEqual(sorted(s.name for s in f.signals), sorted(signals), name)
            for s in f.signals:
                start, length, signed, factor = signals[s.name]
                self.assertEqual((s.start_bit, s.size, bool(s.is_signed)), (start, length, signed),
                                 "%s.%s" % (name, s.name))
                self.assertTrue(s.is_little_endian, "%s.%s" % (name, s.name))
                self.assertAlmostEqual(float(s.factor), factor, places=15)

    @unittest.skipUnless(FRAMES, "APRT_CAN_FRAMES not set (the can_tests fixture writes it)")
    def test_decodes_the_encoders_frames(self):
        by_id = {f.arbitration_id.id: f for f in self.db.frames}
        n = 0
        with open(FRAMES) as fh:
            for line in fh:
                e = json.loads(line)
                values = {}
                for fr in e["frames"]:
                    data = bytes.fromhex(fr["data"])
                    msg = by_id[fr["id"]]
                    dec = {k: v.phys_value for k, v in msg.decode(data).items()}
                    self.assertEqual(int(dec["E2E_CRC"]), crc8_j1850(fr["id"], data))
                    self.assertEqual(int(dec["E2E_Counter"]), e["counter"])
                    values[msg.name] = dec
                for prefix, names, pos_tol in (
                        ("classic", ("APRT_Status", "APRT_PosXY", "APRT_PosZQw", "APRT_QuatYZ",
                                     "APRT_Time"), 0.005),
                        ("fd", ("APRT_PoseFD",) * 5, 0.0005)):
                    st, xy, zq, qyz, tm = (values[k] for k in names)
                    self.assertAlmostEqual(float(xy["PosX"]), e["x"], delta=pos_tol + 1e-9)
                    self.assertAlmostEqual(float(xy["PosY"]), e["y"], delta=pos_tol + 1e-9)
                    self.assertAlmostEqual(float(zq["PosZ"]), e["z"], delta=pos_tol + 1e-9)
                    for sig, key in (("QuatW", "qw"), ("QuatX", "qx")):
                        self.assertAlmostEqual(float(zq[sig]), e[key], delta=0.5 / 32767 + 1e-12)
                    for sig, key in (("QuatY", "qy"), ("QuatZ", "qz")):
                        self.assertAlmostEqual(float(qyz[sig]), e[key], delta=0.5 / 32767 + 1e-12)
                    self.assertEqual(state_raw(st["State"]), e["state"])  # VAL_ names decoded
                    self.assertEqual(int(st["Flags"]), e["flags"])
                    self.assertEqual(int(st["Valid"]), e["valid"], prefix)
                    t = int(tm["TimestampUs"])
                    self.assertEqual(t, e["t"] if prefix == "fd" else e["t"] % (1 << 48))
                n += 1
        self.assertGreater(n, 0)


def state_raw(state):
    names = ["STARTING", "RUNNING", "DEGRADED", "FAULT", "STOPPING"]
    return names.index(state) if isinstance(state, str) else int(state)


if __name__ == "__main__":
    unittest.main()
