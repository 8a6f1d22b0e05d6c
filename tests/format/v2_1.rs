//! Format 2.1: the worked examples with rises and deep VOs, and rows S22/B14.

#[allow(unused_imports)]
use super::*;

#[test]
fn doc_2_1_examples_are_the_encoder_output_and_read_back() {
    let f = doc_frame();
    let cells = doc_cells_2_1();
    let bytes = encode_store_with(&f, &cells, &doc_scene()).unwrap();
    assert_eq!(bytes, doc_hex("store-2.1"));
    let st = Store::parse(&bytes).unwrap();
    assert_eq!(st.version(), (2, 1));
    assert_eq!(st.cell(0).unwrap(), cells[0]);
    let blob = encode_blob(&f, 0, &cells[0]).unwrap();
    assert_eq!(blob, doc_hex("blob-2.1-cell0"));
    assert_eq!(decode_blob(&f, &blob).unwrap(), (0, cells[0]));
    // Section 13's worked figures.
    let rec = cells[0];
    let view = f.cell_view(0, rec.stand()).unwrap();
    assert_eq!((view.e0, view.e1), (163.5, 167.0));
    let g0 = f.dequantize(0, rec.stand(), &rec.vos()[0]).unwrap();
    assert_eq!((g0.g, g0.h), (162.0, 175.20703125));
    let g1 = f.dequantize(0, rec.stand(), &rec.vos()[1]).unwrap();
    assert_eq!((g1.g, g1.h), (160.0, 509.9446951953614));
    // Without the rise and the deep VO, the same records write a 2.0 file.
    let plain = encode_store_with(&f, &doc_cells(), &doc_scene()).unwrap();
    assert_eq!(&plain[8..12], &[2, 0, 0, 0]);
}

#[test]
fn s22_b14_bad_rise_and_rise_values_where_they_cannot_be() {
    let f = doc_frame();
    let good = doc_hex("store-2.1");
    // Rise 0 (offset 0xa6), and ground 4 + rise 252 > 255.
    for (rise, what) in [(0u8, "zero"), (252, "past 255")] {
        let mut s = good.clone();
        s[0xa6] = rise;
        fix_store_crc(&mut s);
        assert_eq!(
            Store::parse(&s).unwrap_err(),
            FormatError::BadRise {
                cell: 0,
                ground: 4,
                rise,
                offset: 0xa6
            },
            "{what}"
        );
    }
    let mut b = doc_hex("blob-2.1-cell0");
    b[0x0b] = 0;
    fix_blob_crc(&mut b);
    assert!(matches!(
        decode_blob(&f, &b).unwrap_err(),
        FormatError::BadRise { rise: 0, .. }
    ));
    // 11..=20 need ground bytes: a flat frame refuses them (S10, B4); 21 is reserved.
    let flat = Frame {
        ground_step: 0.0,
        ..f
    };
    let mut b = doc_hex("blob-2.1-cell0");
    fix_blob_crc(&mut b);
    assert!(matches!(
        decode_blob(&flat, &b).unwrap_err(),
        FormatError::BadIndexByte { value: 12, .. }
    ));
    let mut s = good.clone();
    s[0x9e] = 21;
    fix_store_crc(&mut s);
    assert!(matches!(
        Store::parse(&s).unwrap_err(),
        FormatError::BadIndexByte { value: 21, .. }
    ));
    // The encoder refuses what a decoder would.
    let over = CellRecord::new(250, &[q(196, 376, 336, 376, 5)])
        .unwrap()
        .with_rise(6);
    assert!(matches!(
        encode_store_with(
            &f,
            &[over, CellRecord::Skipped, CellRecord::EMPTY],
            &doc_scene()
        ),
        Err(FormatError::BadRise { .. })
    ));
}
