import pytest

from data_pipeline.record import CorruptRecordError, Record, decode_record, encode_record


def _record() -> Record:
    return Record(key="cabinet/abc/0", image_png=b"\x89PNG-image", seg_png=b"\x89PNG-seg!",
                  prompt="Parts ...", target='{"nodes":{}}', program="a = cube()",
                  meta={"category": "cabinet", "split": "train", "scale": 0.8})


def test_round_trip_keeps_every_field():
    rec = _record()
    assert decode_record(encode_record(rec)) == rec


def test_encoding_is_deterministic():
    assert encode_record(_record()) == encode_record(_record())


@pytest.mark.parametrize("cut", [0, 3, 9, 40, -1])
def test_truncated_records_raise(cut):
    blob = encode_record(_record())
    with pytest.raises(CorruptRecordError):
        decode_record(blob[:cut])


def test_bad_magic_and_bad_header_raise():
    blob = encode_record(_record())
    with pytest.raises(CorruptRecordError, match="magic"):
        decode_record(b"XXXXX" + blob[5:])
    with pytest.raises(CorruptRecordError, match="header"):
        decode_record(blob[:9] + b"!" + blob[10:])
