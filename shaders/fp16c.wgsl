// FP16C: a 16-bit float with one mantissa bit more than IEEE half for the small deviations f_i -
// w_i (as FluidX3D's FP16C): 1 sign bit, 4 exponent bits, 11 mantissa bits, no infinities. The
// range ends below 2 (|f_i - w_i| < 1 in any healthy cell); normal from 2^-14, subnormal steps of
// 2^-25 below. Relative rounding error at most 2^-12, half FP16S's. Larger values, infinities and
// NaN saturate to +-(2 - 2^-11), which the health check's density bound then catches.
fn encode16(x: f32) -> u32 {
    let bits = bitcast<u32>(x);
    let sign = (bits >> 16u) & 0x8000u;
    let a = bits & 0x7fffffffu;
    // Normal: the f32 exponent rebiased (127 -> 15) and the mantissa rounded to 11 bits, to
    // nearest even (a carry moves into the exponent).
    let n = a - (112u << 23u);
    let normal = min((n + 0x7ffu + ((n >> 12u) & 1u)) >> 12u, 0x7fffu);
    let subnormal = u32(round(ldexp(abs(x), 25)));
    let magnitude = select(subnormal, normal, a >= (113u << 23u));
    return sign | select(magnitude, 0x7fffu, a >= 0x40000000u);
}

fn decode16(h: u32) -> f32 {
    let magnitude = h & 0x7fffu;
    let normal = bitcast<f32>((magnitude << 12u) + (112u << 23u));
    let value = select(ldexp(f32(magnitude), -25), normal, magnitude >= 0x800u);
    return select(value, -value, (h & 0x8000u) != 0u);
}
