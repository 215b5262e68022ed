//! The shader preprocessor: repeats each `//#for v` ... `//#end` block for the 19 directions,
//! replacing {v} with the direction, {v.o} with its opposite, {v.cx} {v.cy} {v.cz} with its
//! velocity and {v.w} with its weight. Blocks may nest (with different variable names).

use super::d3q19::{opposite, C, W};

/// Expands every loop block of `source`.
pub fn unroll(source: &str) -> String {
    let lines: Vec<&str> = source.lines().collect();
    let mut out = String::with_capacity(source.len() * 4);
    let mut i = 0;
    while i < lines.len() {
        let Some(var) = loop_variable(lines[i]) else {
            out.push_str(lines[i]);
            out.push('\n');
            i += 1;
            continue;
        };
        let end = matching_end(&lines, i);
        let body = lines[i + 1..end].join("\n") + "\n";
        for d in 0..19 {
            out.push_str(&unroll(&substitute(&body, var, d)));
        }
        i = end + 1;
    }
    out
}

fn loop_variable(line: &str) -> Option<&str> {
    line.trim().strip_prefix("//#for ").map(str::trim)
}

/// Index of the `//#end` closing the block opened at `start`.
fn matching_end(lines: &[&str], start: usize) -> usize {
    let mut depth = 0;
    for (k, line) in lines.iter().enumerate().skip(start) {
        if loop_variable(line).is_some() {
            depth += 1;
        } else if line.trim() == "//#end" {
            depth -= 1;
            if depth == 0 {
                return k;
            }
        }
    }
    panic!("shader: //#for at line {} has no //#end", start + 1);
}

fn substitute(body: &str, var: &str, d: usize) -> String {
    body.replace(&format!("{{{var}.o}}"), &opposite(d).to_string())
        .replace(&format!("{{{var}.cx}}"), &C[d][0].to_string())
        .replace(&format!("{{{var}.cy}}"), &C[d][1].to_string())
        .replace(&format!("{{{var}.cz}}"), &C[d][2].to_string())
        .replace(&format!("{{{var}.w}}"), &format!("{:.10e}", W[d]))
        .replace(&format!("{{{var}}}"), &d.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_are_repeated_and_nested() {
        let src = "a\n//#for i\nx{i}={i.o};\n//#for j\ny{i}{j}\n//#end\n//#end\nb\n";
        let out = unroll(src);
        assert!(out.starts_with("a\nx0=0;\ny00\ny01\n"), "{out}");
        assert!(out.contains("x1=2;"));
        assert!(out.contains("y1818"));
        assert_eq!(out.matches('y').count(), 361);
        assert!(out.ends_with("b\n"));
    }
}
