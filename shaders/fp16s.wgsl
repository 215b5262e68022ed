// FP16S: IEEE 754 half precision (1 sign, 5 exponent, 10 mantissa bits) of f_i - w_i, with the
// core builtins pack2x16float and unpack2x16float (no shader-f16 extension: every device,
// lavapipe included). Relative rounding error at most 2^-11; subnormal steps of 2^-24.
fn encode16(x: f32) -> u32 {
    return pack2x16float(vec2<f32>(x, 0.0)) & 0xffffu;
}

fn decode16(h: u32) -> f32 {
    return unpack2x16float(h).x;
}
