//! Records shared by the tests: metaplate's units, nodes and responses.

#![allow(dead_code, clippy::approx_constant)] // 3.14159265358979 is a value with 15 digits, not π

use metaplate_uff::{
    Complex64, Function58, FunctionHeader, FunctionType, Node, Nodes2411, Ordinate, UffDecoder, UffRecord, Units164,
};

/// Two grid points and an actuator, in metres (the fixtures' nodes).
pub fn nodes() -> Nodes2411 {
    let node = |label, position_m| Node {
        label,
        export_coordinate_system: 0,
        displacement_coordinate_system: 0,
        color: 0,
        position_m,
    };
    Nodes2411 { nodes: vec![node(1, [0.0, 0.0, 0.0]), node(2, [0.0125, 0.0, 0.0]), node(1001, [-0.02, 0.15, 0.0])] }
}

/// The response of grid point 2 to actuator 1001, as the fixtures hold it.
pub fn function(function_type: FunctionType, ordinate: Ordinate) -> Function58 {
    let step = match function_type {
        FunctionType::TimeResponse => 1.0 / 48000.0,
        _ => 2.5,
    };
    let header = FunctionHeader::velocity_over_force(function_type, 2, 1001, 0.0, step, "metaplate point 2 actuator 1");
    Function58 { header, ordinate }
}

/// The fixtures' real values: zero, signs, small and large exponents, more digits than any format keeps.
pub fn real_values() -> Vec<f64> {
    vec![0.0, 1.5e-3, -2.25e-7, 3.14159265358979, -12345.678901234, 6.02214076e23, 1.0e-30]
}

/// The fixtures' complex values.
pub fn complex_values() -> Vec<Complex64> {
    let im = [-1.0, 2.5e-9, 0.0, -7.77777777777e2, 1.0e-5];
    real_values().iter().zip(im).map(|(&re, im)| Complex64::new(re, im)).collect()
}

/// Decodes `bytes` pushed in pieces of `chunk` bytes; every result in order.
pub fn decode_in_chunks(bytes: &[u8], chunk: usize) -> Vec<Result<UffRecord, metaplate_uff::DecodeError>> {
    let mut decoder = UffDecoder::new();
    let mut out = Vec::new();
    for piece in bytes.chunks(chunk.max(1)) {
        decoder.push(piece);
        out.extend(decoder.records());
    }
    decoder.finish();
    out.extend(decoder.records());
    out
}

/// Decodes `bytes` whole.
pub fn decode(bytes: &[u8]) -> Vec<Result<UffRecord, metaplate_uff::DecodeError>> {
    decode_in_chunks(bytes, bytes.len())
}

/// The SI units record.
pub fn units() -> Units164 {
    Units164::si()
}
