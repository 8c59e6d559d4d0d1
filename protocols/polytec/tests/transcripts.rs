//! Request lines as PLACE writes them (github.com/PALab/place, `place/plugins/polytec/polytec.py`), decoded and
//! encoded byte for byte.

use metaplate_polytec_protocol::{Device, Reply, Request, RequestDecoder, VelocityRange, Verb, split_list};

/// Lines PLACE's plugin sends, verbatim with their LF (functions named beside each).
const PLACE_LINES: [&str; 6] = [
    "GetDevInfo,Controller,0,Name\n",        // _get_controller_name
    "Set,VeloDec,1,Range,5mm/s/V\n",         // _set_range with id 'VeloDec,1' (a VD-09)
    "Get,VeloDec,1,Range\n",                 // _get_range
    "Get,SignalLevel,0,Value\n",             // _get_signal_level
    "Set,SensorHead,0,AutoFocusSpan,Full\n", // _autofocus_vibrometer
    "Set,SensorHead,0,AutoFocus,Search\n",   // _autofocus_vibrometer
];

#[test]
fn place_lines_decode_and_encode_back_byte_for_byte() {
    let mut decoder = RequestDecoder::new();
    decoder.push(PLACE_LINES.concat().as_bytes());
    for line in PLACE_LINES {
        let request = decoder.poll().unwrap().unwrap();
        assert_eq!(request.encode(), line.as_bytes());
    }
    assert!(decoder.poll().is_none());
}

#[test]
fn constructors_spell_the_manual_syntax() {
    let set = Request::set(Device::VeloDec, 0, "Range", "5mm/s/V").unwrap();
    assert_eq!(set.encode(), b"Set,VeloDec,0,Range,5mm/s/V\n");
    assert!(!set.verb().expects_reply());
    let info = Request::dev_info(Device::VeloDec, 0, "Range").unwrap();
    assert_eq!(
        (info.verb(), info.device(), info.index(), info.attribute()),
        (Verb::GetDevInfo, Device::VeloDec, 0, "Range")
    );
    // PLACE's custom autofocus area: a value with a comma of its own.
    let area = Request::parse("Set,SensorHead,0,AutoFocusArea,100,2000").unwrap();
    assert_eq!(area.value(), Some("100,2000"));
}

#[test]
fn replies_are_classified_echo_not_available_or_text() {
    let get = Request::get(Device::VeloDec, 0, "Range").unwrap();
    assert_eq!(Reply::classify("Get,VeloDec,0,Range", &get), Reply::Echo);
    // The late echo of an earlier Set is no answer either.
    assert_eq!(Reply::classify("Set,Interface,0,Echo,Off", &get), Reply::Echo);
    // PLACE (old vibrometer.py): "Not Available" for a missing decoder's ranges, "not Installed" for its name.
    assert_eq!(Reply::classify("Not Available", &get), Reply::NotAvailable);
    assert_eq!(Reply::classify("not Installed", &get), Reply::NotAvailable);
    assert_eq!(Reply::classify("5mm/s/V ", &get), Reply::Text("5mm/s/V".into()));
    let ranges: Vec<f64> = split_list("1mm/s/V,5mm/s/V, 25mm/s/V,,125mm/s/V,1000mm/s/V")
        .into_iter()
        .map(|r| VelocityRange::parse(r).unwrap().m_s_per_v())
        .collect();
    assert_eq!(ranges.len(), 5);
    assert!((ranges[4] - 1.0).abs() < 1e-12);
}
