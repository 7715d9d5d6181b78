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
//!
//! A second repair is for naga 30's SPIR-V front-end, not for naga's output: it reads
//! `OpImageQuerySize[Lod]` of an arrayed image as the size without the layer count (a
//! `vec2`; "TODO: handle arrays" in `front/spv/image.rs`), so the `Restrict` clamp of a
//! `textureLoad` from a `texture_2d_array` (`min(coords, size - 1)` on a `vec3`) does not
//! validate there, although the module is valid SPIR-V. [`fix_arrayed_load_clamps`] feeds
//! that clamp the query's width and height only, with the layer bound `u32::MAX`: the texel
//! coordinates stay clamped, the layer index is left as the kernel computed it (`ivsv_rectify`'s
//! VPL index, below the layer count the manifest gives the texture). Queries used for
//! anything but such a clamp are left alone.

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

const OP_TYPE_IMAGE: u32 = 25;
const OP_FUNCTION: u32 = 54;
const OP_LOAD: u32 = 61;
const OP_VECTOR_SHUFFLE: u32 = 79;
const OP_COMPOSITE_CONSTRUCT: u32 = 80;
const OP_IMAGE_QUERY_SIZE_LOD: u32 = 103;
const OP_IMAGE_QUERY_SIZE: u32 = 104;
const OP_ISUB: u32 = 130;
/// `Dim2D` of `OpTypeImage`.
const DIM_2D: u32 = 1;

/// Returns `words` with every size query of a 2D arrayed image whose only use is the
/// `Restrict` clamp (`OpISub %v3uint %size %ones`) replaced by `(width, height, u32::MAX)`
/// built from the query's first two components (see the module docs), and the number of
/// queries rewritten.
///
/// # Errors
///
/// A message when the words are not a SPIR-V module.
pub fn fix_arrayed_load_clamps(words: &[u32]) -> Result<(Vec<u32>, usize), String> {
    if words.len() < HEADER_WORDS || words[0] != 0x0723_0203 {
        return Err("not a SPIR-V module".to_owned());
    }
    let list = instructions(words)?;
    let mut uints: Vec<u32> = Vec::new();
    let mut vectors: HashMap<u32, (u32, u32)> = HashMap::new();
    let mut arrayed_2d: Vec<u32> = Vec::new();
    let mut loaded: HashMap<u32, u32> = HashMap::new();
    let mut uses: HashMap<u32, Vec<(u32, usize)>> = HashMap::new();
    let mut max_constant = None;
    for &(at, count) in &list {
        let op = words[at] & 0xffff;
        let operands = &words[at + 1..at + count];
        match (op, operands) {
            (OP_TYPE_INT, &[id, 32, 0]) => uints.push(id),
            (OP_TYPE_VECTOR, &[id, component, n]) => {
                vectors.insert(id, (component, n));
            }
            (OP_TYPE_IMAGE, &[id, _, dim, _, 1, ..]) if dim == DIM_2D => arrayed_2d.push(id),
            (OP_LOAD, &[ty, id, ..]) => {
                loaded.insert(id, ty);
            }
            (OP_CONSTANT, &[ty, id, u32::MAX]) if uints.contains(&ty) => {
                max_constant.get_or_insert(id);
            }
            _ => {}
        }
        // Operand uses (result ids of later instructions included: only ISub's first
        // operand is trusted below).
        if op == OP_ISUB && operands.len() == 4 {
            uses.entry(operands[2]).or_default().push((op, 0));
            uses.entry(operands[3]).or_default().push((op, 1));
        } else if op != OP_IMAGE_QUERY_SIZE && op != OP_IMAGE_QUERY_SIZE_LOD {
            for &w in operands {
                uses.entry(w).or_default().push((op, usize::MAX));
            }
        } else if operands.len() >= 3 {
            for &w in &operands[2..] {
                uses.entry(w).or_default().push((op, usize::MAX));
            }
        }
    }
    let Some(&uint) = uints.first() else {
        return Ok((words.to_vec(), 0));
    };
    let find_vector = |n: u32| {
        vectors
            .iter()
            .find(|(_, (c, k))| *c == uint && *k == n)
            .map(|(id, _)| *id)
    };
    let (Some(v2uint), Some(v3uint)) = (find_vector(2), find_vector(3)) else {
        return Ok((words.to_vec(), 0));
    };
    let mut bound = words[3];
    let max_id = match max_constant {
        Some(id) => id,
        None => {
            bound += 1;
            bound - 1
        }
    };
    let mut out = Vec::with_capacity(words.len() + 16);
    out.extend_from_slice(&words[..HEADER_WORDS]);
    let mut fixed = 0;
    let mut constant_placed = max_constant.is_some();
    for &(at, count) in &list {
        let op = words[at] & 0xffff;
        let inst = &words[at..at + count];
        if op == OP_FUNCTION && !constant_placed {
            // Globals end at the first function: the new constant goes there (it is only
            // emitted if some query is rewritten; otherwise the id stays unused).
            constant_placed = true;
            out.extend([(4 << 16) | OP_CONSTANT, uint, max_id, u32::MAX]);
        }
        let query = (op == OP_IMAGE_QUERY_SIZE_LOD || op == OP_IMAGE_QUERY_SIZE)
            && inst[1] == v3uint
            && loaded
                .get(&inst[3])
                .is_some_and(|ty| arrayed_2d.contains(ty))
            && uses
                .get(&inst[2])
                .is_some_and(|u| u.len() == 1 && u[0] == (OP_ISUB, 0));
        if !query {
            out.extend_from_slice(inst);
            continue;
        }
        let result = inst[2];
        let (q, xy) = (bound, bound + 1);
        bound += 2;
        let mut requery = inst.to_vec();
        requery[2] = q;
        out.extend_from_slice(&requery);
        out.extend([(7 << 16) | OP_VECTOR_SHUFFLE, v2uint, xy, q, q, 0, 1]);
        out.extend([
            (5 << 16) | OP_COMPOSITE_CONSTRUCT,
            v3uint,
            result,
            xy,
            max_id,
        ]);
        fixed += 1;
    }
    if fixed == 0 {
        return Ok((words.to_vec(), 0));
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

    /// `%uint`, `%v2uint`, `%v3uint`, a 2D arrayed image type, and a function that loads
    /// the image, queries its size and subtracts ones (the `Restrict` clamp's first step).
    fn arrayed_module(extra_use: bool) -> Vec<u32> {
        let mut w = vec![0x0723_0203, 0x0001_0000, 0, 30, 0];
        w.extend(inst(OP_TYPE_INT, &[1, 32, 0])); // %uint
        w.extend(inst(OP_TYPE_VECTOR, &[2, 1, 2])); // %v2uint
        w.extend(inst(OP_TYPE_VECTOR, &[3, 1, 3])); // %v3uint
        w.extend(inst(OP_TYPE_IMAGE, &[4, 1, DIM_2D, 0, 1, 0, 1, 0])); // arrayed
        w.extend(inst(OP_CONSTANT, &[1, 5, 1])); // %uint_1
        w.extend(inst(OP_CONSTANT_COMPOSITE, &[3, 6, 5, 5, 5])); // ones
        w.extend(inst(OP_FUNCTION, &[1, 7, 0, 8]));
        w.extend(inst(OP_LOAD, &[4, 9, 10])); // %9 = the image
        w.extend(inst(OP_IMAGE_QUERY_SIZE_LOD, &[3, 11, 9, 5]));
        w.extend(inst(OP_ISUB, &[3, 12, 11, 6]));
        if extra_use {
            w.extend(inst(OP_ISUB, &[3, 13, 6, 11]));
        }
        w
    }

    #[test]
    fn arrayed_size_queries_feed_the_clamp_width_and_height_only() {
        let (out, fixed) = fix_arrayed_load_clamps(&arrayed_module(false)).unwrap();
        assert_eq!(fixed, 1);
        // The new u32::MAX constant (id 30) before the function; the query now defines %31,
        // %32 = its x and y, %11 = (x, y, u32::MAX); the ISub is unchanged.
        let mut expected = arrayed_module(false);
        let function = expected.len() - 4 - 5 - 5 - 5;
        expected.splice(function..function, inst(OP_CONSTANT, &[1, 30, u32::MAX]));
        let query = expected.len() - 5 - 5;
        expected.splice(
            query..query + 5,
            [
                inst(OP_IMAGE_QUERY_SIZE_LOD, &[3, 31, 9, 5]),
                inst(OP_VECTOR_SHUFFLE, &[2, 32, 31, 31, 0, 1]),
                inst(OP_COMPOSITE_CONSTRUCT, &[3, 11, 32, 30]),
            ]
            .concat(),
        );
        expected[3] = 33;
        assert_eq!(out, expected);
    }

    #[test]
    fn arrayed_size_queries_with_other_uses_are_left_alone() {
        let module = arrayed_module(true);
        assert_eq!(fix_arrayed_load_clamps(&module).unwrap(), (module, 0));
        assert!(fix_arrayed_load_clamps(&[1, 2, 3]).is_err());
    }
}
