//! A word-level repair of naga 30's SPIR-V output: with the `Restrict` image-load bounds
//! check, naga clamps `textureLoad` coordinates with `min(coords, size - 1)` and builds the
//! vector of ones from its signed `1` constant even when the coordinates are unsigned:
//! `%c = OpConstantComposite %v2uint %int_1 %int_1`. SPIR-V requires constituents of the
//! vector's component type (the Vulkan validation layers report it, gfx-rs/wgpu#4581, and
//! naga's own SPIR-V front-end, which wgpu uses for `ShaderSource::SpirV`, rejects the
//! module: "Composing 0's component type is not expected"); spirv-val 2023.1 lets it pass.
//!
//! [`fix_constant_composite_signedness`] rewrites every such constituent to a constant of
//! the component type with the same bits (an existing one, else a new `OpConstant` placed
//! just before the composite). Integers of the same width with the same bits are the same
//! value for `OpISub` and `UMin`, so the code computes exactly what naga meant.

use std::collections::HashMap;

const OP_TYPE_INT: u32 = 21;
const OP_TYPE_VECTOR: u32 = 23;
const OP_CONSTANT: u32 = 43;
const OP_CONSTANT_COMPOSITE: u32 = 44;
const HEADER_WORDS: usize = 5;

/// One instruction: its start and length in words.
fn instructions(words: &[u32]) -> Result<Vec<(usize, usize)>, String> {
    let mut out = Vec::new();
    let mut at = HEADER_WORDS;
    while at < words.len() {
        let count = (words[at] >> 16) as usize;
        if count == 0 || at + count > words.len() {
            return Err(format!("malformed SPIR-V instruction at word {at}"));
        }
        out.push((at, count));
        at += count;
    }
    Ok(out)
}

/// Returns `words` with every integer constituent of an integer-vector
/// `OpConstantComposite` retyped to the vector's component type (see the module docs), and
/// the number of constituents rewritten.
///
/// # Errors
///
/// A message when the words are not a SPIR-V module.
pub fn fix_constant_composite_signedness(words: &[u32]) -> Result<(Vec<u32>, usize), String> {
    if words.len() < HEADER_WORDS || words[0] != 0x0723_0203 {
        return Err("not a SPIR-V module".to_owned());
    }
    let list = instructions(words)?;
    // Integer types (id -> width, signed), vectors (id -> component type), scalar
    // constants (id -> type, value words) and the reverse map.
    let mut ints: HashMap<u32, (u32, u32)> = HashMap::new();
    let mut vectors: HashMap<u32, u32> = HashMap::new();
    let mut constants: HashMap<u32, (u32, Vec<u32>)> = HashMap::new();
    let mut by_value: HashMap<(u32, Vec<u32>), u32> = HashMap::new();
    for &(at, count) in &list {
        let op = words[at] & 0xffff;
        let operands = &words[at + 1..at + count];
        match (op, operands) {
            (OP_TYPE_INT, &[id, width, signed]) => {
                ints.insert(id, (width, signed));
            }
            (OP_TYPE_VECTOR, &[id, component, _]) => {
                vectors.insert(id, component);
            }
            (OP_CONSTANT, [ty, id, value @ ..]) => {
                constants.insert(*id, (*ty, value.to_vec()));
                by_value.entry((*ty, value.to_vec())).or_insert(*id);
            }
            _ => {}
        }
    }
    let mut bound = words[3];
    let mut out = Vec::with_capacity(words.len() + 8);
    out.extend_from_slice(&words[..HEADER_WORDS]);
    let mut fixed = 0;
    for &(at, count) in &list {
        let op = words[at] & 0xffff;
        let inst = &words[at..at + count];
        let component = (op == OP_CONSTANT_COMPOSITE && count >= 3)
            .then(|| vectors.get(&inst[1]).copied())
            .flatten()
            .filter(|c| ints.contains_key(c));
        let Some(component) = component else {
            out.extend_from_slice(inst);
            continue;
        };
        let mut rewritten = inst.to_vec();
        for slot in &mut rewritten[3..] {
            let Some((ty, value)) = constants.get(slot) else {
                continue;
            };
            if *ty == component || ints.get(ty).map(|t| t.0) != ints.get(&component).map(|t| t.0) {
                continue;
            }
            let key = (component, value.clone());
            let id = match by_value.get(&key) {
                Some(&id) => id,
                None => {
                    let id = bound;
                    bound += 1;
                    out.push(((3 + value.len() as u32) << 16) | OP_CONSTANT);
                    out.push(component);
                    out.push(id);
                    out.extend_from_slice(value);
                    by_value.insert(key, id);
                    id
                }
            };
            *slot = id;
            fixed += 1;
        }
        out.extend_from_slice(&rewritten);
    }
    out[3] = bound;
    Ok((out, fixed))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inst(op: u32, operands: &[u32]) -> Vec<u32> {
        let mut v = vec![((operands.len() as u32 + 1) << 16) | op];
        v.extend_from_slice(operands);
        v
    }

    /// `%int`, `%uint`, `%v2uint`, `%int_1`, `%c = OpConstantComposite %v2uint %int_1
    /// %int_1`, plus `%uint_1` when `with_uint_one`.
    fn module(with_uint_one: bool) -> Vec<u32> {
        let mut w = vec![0x0723_0203, 0x0001_0000, 0, 20, 0];
        w.extend(inst(OP_TYPE_INT, &[1, 32, 1])); // %int
        w.extend(inst(OP_TYPE_INT, &[2, 32, 0])); // %uint
        w.extend(inst(OP_TYPE_VECTOR, &[3, 2, 2])); // %v2uint
        w.extend(inst(OP_CONSTANT, &[1, 4, 1])); // %int_1
        if with_uint_one {
            w.extend(inst(OP_CONSTANT, &[2, 5, 1])); // %uint_1
        }
        w.extend(inst(OP_CONSTANT_COMPOSITE, &[3, 6, 4, 4]));
        w
    }

    #[test]
    fn retypes_signed_constituents_of_unsigned_vectors() {
        let (out, fixed) = fix_constant_composite_signedness(&module(false)).unwrap();
        assert_eq!(fixed, 2);
        // A new %uint 1 (id 20, the old bound) before the composite, which now uses it.
        let tail = &out[out.len() - 9..];
        assert_eq!(tail[..4], inst(OP_CONSTANT, &[2, 20, 1])[..]);
        assert_eq!(tail[4..], inst(OP_CONSTANT_COMPOSITE, &[3, 6, 20, 20])[..]);
        assert_eq!(out[3], 21, "bound");
    }

    #[test]
    fn reuses_an_existing_constant_and_leaves_valid_modules_alone() {
        let (out, fixed) = fix_constant_composite_signedness(&module(true)).unwrap();
        assert_eq!(fixed, 2);
        assert_eq!(out.len(), module(true).len());
        assert_eq!(
            out[out.len() - 5..],
            inst(OP_CONSTANT_COMPOSITE, &[3, 6, 5, 5])[..]
        );
        let (again, fixed) = fix_constant_composite_signedness(&out).unwrap();
        assert_eq!((again, fixed), (out, 0));
        assert!(fix_constant_composite_signedness(&[1, 2, 3]).is_err());
    }
}
