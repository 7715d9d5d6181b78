//! Branches whose condition depends on uniform-buffer values only, found in a kernel's naga
//! IR.
//!
//! lavapipe (Mesa's Vulkan driver on llvmpipe, the machine every test and bench here runs on)
//! specialises a compute shader on the values of its uniforms when one of its `if` conditions
//! (or a loop's exit test, with a constant or uniform start and step) reads nothing but
//! uniform-buffer values at constant offsets and constants (`lvp_find_inlinable_uniforms`):
//! then at every dispatch it clones the shader's NIR, substitutes the values, optimises it
//! again and compiles it (from Mesa's shader cache after the first time). That cost is paid
//! per dispatch whatever the dispatch size: `raymarch`'s epipolar samples pass took 6.9-7.7
//! ms at 1280x720 with its jitter `if` on a uniform and 3.3-4.2 ms with a `select` in its
//! place, its `_fallback` pass 1.3-1.7 ms against 0.5 (docs/roofline.md, "Stop 46").
//! Kernels therefore keep such conditions out of their control flow (a `select`, or a value
//! the shader reads from elsewhere), and [`uniform_branches`] finds the ones left.
//!
//! The analysis mirrors lavapipe's on the naga IR, call-site by call-site (NIR inlines every
//! function): a value is uniform when it derives, through arithmetic, comparisons, selects,
//! conversions and component access, from loads of `var<uniform>` data at constant indices
//! and from constants. A local variable is uniform when every value stored to it is (a loop
//! counter starting at a constant and stepped by a constant is, so a loop bounded by a
//! uniform counts, as in lavapipe); anything read from a texture, a storage buffer, a
//! built-in input or a derivative is not.

use std::collections::HashMap;

use naga::{AddressSpace, Block, Expression, Function, Handle, Module, Statement};

/// Uniform dwords lavapipe inlines per uniform buffer (Mesa's `MAX_INLINABLE_UNIFORMS`).
const MAX_INLINABLE_UNIFORMS: u32 = 4;

/// One control-flow condition that reads only uniforms and constants.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UniformBranch {
    /// The function holding the branch (after naga_oil's name mangling).
    pub function: String,
    /// `if`, `switch` or `break if`.
    pub statement: &'static str,
    /// The condition, written out (naga IR; indices for struct members).
    pub condition: String,
    /// The uniform data the condition reads: the global's name and member indices, e.g.
    /// `frame.13.2` for `frame.interleave[2]`.
    pub reads: Vec<String>,
}

impl std::fmt::Display for UniformBranch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "`{} {}` in `{}` (reads {})",
            self.statement,
            self.condition,
            self.function,
            self.reads.join(", ")
        )
    }
}

/// The branches of entry point `entry_point` (and every function it calls) whose condition
/// reads uniforms and constants only, at least one uniform; empty when there is no such entry
/// point.
pub fn uniform_branches(module: &Module, entry_point: &str) -> Vec<UniformBranch> {
    let Some(ep) = module.entry_points.iter().find(|e| e.name == entry_point) else {
        return Vec::new();
    };
    let mut analysis = Analysis {
        module,
        memo: HashMap::new(),
        found: Vec::new(),
    };
    let name = ep.name.clone();
    let args = vec![Kind::Varying; ep.function.arguments.len()];
    analysis.function(&ep.function, &name, &args);
    analysis.found
}

/// What a value derives from.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
enum Kind {
    /// Constants only.
    Const,
    /// Exactly the uniform data at this path (`frame.21.0`): a load, or a member of one.
    Place(String),
    /// Uniform-buffer loads at constant indices (named) and constants.
    Uniform(Vec<String>),
    /// Anything else.
    Varying,
}

impl Kind {
    /// `self` as `Uniform` (a `Place` becomes its one read).
    fn value(self) -> Kind {
        match self {
            Kind::Place(p) => Kind::Uniform(vec![p]),
            k => k,
        }
    }

    fn join(self, other: Kind) -> Kind {
        match (self.value(), other.value()) {
            (Kind::Varying, _) | (_, Kind::Varying) => Kind::Varying,
            (Kind::Const, k) | (k, Kind::Const) => k,
            (Kind::Uniform(mut a), Kind::Uniform(b)) => {
                for r in b {
                    if !a.contains(&r) {
                        a.push(r);
                    }
                }
                Kind::Uniform(a)
            }
            // `value()` leaves no `Place`.
            (a, _) => a,
        }
    }
}

/// Where a pointer expression points.
enum Place {
    /// Into a `var<uniform>`: its name and the indices (None: not at a constant index).
    Uniform(String, Option<Vec<u32>>),
    Local(Handle<naga::LocalVariable>),
    Other,
}

struct Analysis<'m> {
    module: &'m Module,
    /// (function, argument kinds) -> return kind.
    memo: HashMap<(Handle<Function>, Vec<Kind>), Kind>,
    found: Vec<UniformBranch>,
}

/// One function analysed for one call site.
struct Frame<'f> {
    function: &'f Function,
    name: &'f str,
    args: &'f [Kind],
    /// The kind of every local variable read as a value.
    locals: HashMap<Handle<naga::LocalVariable>, Kind>,
    /// Locals given more than one value, as loop counters: the join of their values.
    counters: HashMap<Handle<naga::LocalVariable>, Kind>,
    cache: HashMap<Handle<Expression>, Kind>,
}

impl<'m> Analysis<'m> {
    /// Analyses `function` called with `args`: records its uniform branches (and those of
    /// its callees) and returns the kind of its return value.
    fn function(&mut self, function: &Function, name: &str, args: &[Kind]) -> Kind {
        let mut frame = Frame {
            function,
            name,
            args,
            locals: HashMap::new(),
            counters: HashMap::new(),
            cache: HashMap::new(),
        };
        // How many values each local variable is given (its initialiser included): one, and
        // it is that value; more, and NIR joins them in a phi, which lavapipe does not
        // follow (a loop counter excepted, below).
        let mut stores: HashMap<Handle<naga::LocalVariable>, Vec<Handle<Expression>>> = function
            .local_variables
            .iter()
            .map(|(h, var)| (h, var.init.into_iter().collect()))
            .collect();
        self.stores(&mut frame, &function.body, &mut stores);
        let single: Vec<_> = stores
            .iter()
            .filter(|(_, s)| s.len() == 1)
            .map(|(&v, s)| (v, s[0]))
            .collect();
        for (&v, s) in &stores {
            if s.len() != 1 {
                frame.locals.insert(v, Kind::Varying);
            }
        }
        // Single-value locals, in dependency order (a fixed point; WGSL has no cycles here).
        for (v, _) in &single {
            frame.locals.insert(*v, Kind::Const);
        }
        for _ in 0..64 {
            frame.cache.clear();
            let mut changed = false;
            for &(v, value) in &single {
                let k = self.expr(&mut frame, value);
                if frame.locals.get(&v) != Some(&k) {
                    frame.locals.insert(v, k);
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        // A loop counter: every value it is given derives from constants, uniforms and
        // itself (`i = 0; i = i + 1`); lavapipe inlines a loop exit test comparing one
        // with a uniform.
        for (&v, s) in &stores {
            if s.len() < 2 {
                continue;
            }
            frame.locals.insert(v, Kind::Const);
            frame.cache.clear();
            let k = s
                .iter()
                .fold(Kind::Const, |k, &e| k.join(self.expr(&mut frame, e)));
            frame.locals.insert(v, Kind::Varying);
            frame.counters.insert(v, k);
        }
        frame.cache.clear();
        self.conditions(&mut frame, &function.body, false)
    }

    fn call(&mut self, callee: Handle<Function>, args: Vec<Kind>) -> Kind {
        if let Some(k) = self.memo.get(&(callee, args.clone())) {
            return k.clone();
        }
        // Recursion is not valid WGSL; guard anyway.
        self.memo.insert((callee, args.clone()), Kind::Varying);
        let f = &self.module.functions[callee];
        let name = f.name.clone().unwrap_or_else(|| format!("{callee:?}"));
        let k = self.function(f, &name, &args);
        self.memo.insert((callee, args), k.clone());
        k
    }

    /// Adds to `stores` every value `block` stores to a local variable (a call or atomic
    /// writing through a pointer to one adds the pointer itself: varying).
    fn stores(
        &mut self,
        frame: &mut Frame<'_>,
        block: &Block,
        stores: &mut HashMap<Handle<naga::LocalVariable>, Vec<Handle<Expression>>>,
    ) {
        for stmt in block.iter() {
            match stmt {
                Statement::Store { pointer, value } => {
                    if let Place::Local(v) = self.place(frame, *pointer) {
                        stores.entry(v).or_default().push(*value);
                    }
                }
                Statement::Block(b) => self.stores(frame, b, stores),
                Statement::If { accept, reject, .. } => {
                    self.stores(frame, accept, stores);
                    self.stores(frame, reject, stores);
                }
                Statement::Switch { cases, .. } => {
                    for c in cases {
                        self.stores(frame, &c.body, stores);
                    }
                }
                Statement::Loop {
                    body, continuing, ..
                } => {
                    self.stores(frame, body, stores);
                    self.stores(frame, continuing, stores);
                }
                Statement::Call { arguments, .. } => {
                    for a in arguments {
                        if let Place::Local(v) = self.place(frame, *a) {
                            // Twice: a local written by a call is never single-valued.
                            stores.entry(v).or_default().extend([*a, *a]);
                        }
                    }
                }
                Statement::Atomic { pointer, .. } => {
                    if let Place::Local(v) = self.place(frame, *pointer) {
                        stores.entry(v).or_default().extend([*pointer, *pointer]);
                    }
                }
                _ => {}
            }
        }
    }

    /// Records the uniform conditions of `block` (`in_loop`: it is a loop's body, where an
    /// `if` breaking out is the loop's exit test); returns the join of its return values.
    fn conditions(&mut self, frame: &mut Frame<'_>, block: &Block, in_loop: bool) -> Kind {
        let mut ret = Kind::Const;
        for stmt in block.iter() {
            match stmt {
                Statement::If {
                    condition,
                    accept,
                    reject,
                } => {
                    let exit = in_loop
                        && [accept, reject]
                            .iter()
                            .any(|b| matches!(b.first(), Some(Statement::Break)));
                    self.report(frame, *condition, "if", exit);
                    ret = ret.join(self.conditions(frame, accept, false));
                    ret = ret.join(self.conditions(frame, reject, false));
                }
                Statement::Switch { selector, cases } => {
                    self.report(frame, *selector, "switch", false);
                    for c in cases {
                        ret = ret.join(self.conditions(frame, &c.body, false));
                    }
                }
                Statement::Loop {
                    body,
                    continuing,
                    break_if,
                } => {
                    ret = ret.join(self.conditions(frame, body, true));
                    ret = ret.join(self.conditions(frame, continuing, false));
                    if let Some(c) = break_if {
                        self.report(frame, *c, "break if", true);
                    }
                }
                Statement::Block(b) => ret = ret.join(self.conditions(frame, b, in_loop)),
                Statement::Return { value: Some(v) } => ret = ret.join(self.expr(frame, *v)),
                Statement::Call {
                    function,
                    arguments,
                    ..
                } => {
                    let args = arguments.iter().map(|a| self.expr(frame, *a)).collect();
                    self.call(*function, args);
                }
                _ => {}
            }
        }
        ret
    }

    /// Records `condition` when it reads uniforms and constants only; `exit`: it is a loop's
    /// exit test, where a comparison of a loop counter with a uniform counts too.
    fn report(
        &mut self,
        frame: &mut Frame<'_>,
        condition: Handle<Expression>,
        what: &'static str,
        exit: bool,
    ) {
        let mut kind = self.expr(frame, condition);
        if exit && kind == Kind::Varying {
            kind = self.counter_test(frame, condition);
        }
        if let Kind::Uniform(reads) = kind.value() {
            // lavapipe inlines at most 4 uniform dwords per buffer (MAX_INLINABLE_UNIFORMS):
            // a condition reading more is left alone.
            let dwords: u32 = reads.iter().map(|r| self.dwords(r)).sum();
            if dwords > MAX_INLINABLE_UNIFORMS {
                return;
            }
            let b = UniformBranch {
                function: frame.name.to_owned(),
                statement: what,
                condition: write(frame.function, condition, 4),
                reads,
            };
            if !self.found.contains(&b) {
                self.found.push(b);
            }
        }
    }

    /// The kind of a loop exit test `counter <op> bound` (or its negation) with `counter` a
    /// loop counter: the join of the counter's values and the bound, or varying.
    fn counter_test(&mut self, frame: &mut Frame<'_>, condition: Handle<Expression>) -> Kind {
        let e = &frame.function.expressions;
        let mut c = condition;
        if let Expression::Unary {
            op: naga::UnaryOperator::LogicalNot,
            expr,
        } = e[c]
        {
            c = expr;
        }
        let Expression::Binary { op, left, right } = e[c] else {
            return Kind::Varying;
        };
        use naga::BinaryOperator as B;
        if !matches!(
            op,
            B::Less | B::LessEqual | B::Greater | B::GreaterEqual | B::Equal | B::NotEqual
        ) {
            return Kind::Varying;
        }
        for (a, b) in [(left, right), (right, left)] {
            let counter = match e[a] {
                Expression::Load { pointer } => match e[pointer] {
                    Expression::LocalVariable(v) => frame.counters.get(&v).cloned(),
                    _ => None,
                },
                _ => None,
            };
            if let Some(k) = counter {
                return k.join(self.expr(frame, b));
            }
        }
        Kind::Varying
    }

    /// The 32-bit words of uniform data at `read` (`frame.21.0`, `.[c]` an array element).
    fn dwords(&self, read: &str) -> u32 {
        let mut parts = read.split('.');
        let name = parts.next().unwrap_or_default();
        let Some((_, g)) = self
            .module
            .global_variables
            .iter()
            .find(|(h, g)| g.name.as_deref().unwrap_or(&format!("{h:?}")) == name)
        else {
            return 1;
        };
        let types = &self.module.types;
        let mut ty = &types[g.ty].inner;
        for part in parts {
            ty = match ty {
                naga::TypeInner::Struct { members, .. } => match part.parse::<usize>() {
                    Ok(i) if i < members.len() => &types[members[i].ty].inner,
                    _ => return 1,
                },
                naga::TypeInner::Array { base, .. } => &types[*base].inner,
                naga::TypeInner::Vector { .. } | naga::TypeInner::Matrix { .. } => return 1,
                _ => return 1,
            };
        }
        match ty {
            naga::TypeInner::Scalar(_) => 1,
            naga::TypeInner::Vector { size, .. } => *size as u32,
            naga::TypeInner::Matrix { columns, rows, .. } => *columns as u32 * *rows as u32,
            _ => MAX_INLINABLE_UNIFORMS + 1,
        }
    }

    fn place(&mut self, frame: &mut Frame<'_>, pointer: Handle<Expression>) -> Place {
        match frame.function.expressions[pointer] {
            Expression::GlobalVariable(g) => {
                let var = &self.module.global_variables[g];
                if var.space == AddressSpace::Uniform {
                    let name = var.name.clone().unwrap_or_else(|| format!("{g:?}"));
                    Place::Uniform(name, Some(Vec::new()))
                } else {
                    Place::Other
                }
            }
            Expression::LocalVariable(v) => Place::Local(v),
            Expression::AccessIndex { base, index } => match self.place(frame, base) {
                Place::Uniform(n, Some(mut path)) => {
                    path.push(index);
                    Place::Uniform(n, Some(path))
                }
                p => p,
            },
            Expression::Access { base, index } => {
                let constant = self.expr(frame, index) == Kind::Const;
                match self.place(frame, base) {
                    Place::Uniform(n, Some(mut path)) if constant => {
                        path.push(u32::MAX);
                        Place::Uniform(n, Some(path))
                    }
                    Place::Uniform(n, _) => Place::Uniform(n, None),
                    p => p,
                }
            }
            _ => Place::Other,
        }
    }

    fn expr(&mut self, frame: &mut Frame<'_>, h: Handle<Expression>) -> Kind {
        if let Some(k) = frame.cache.get(&h) {
            return k.clone();
        }
        let k = self.expr_uncached(frame, h);
        frame.cache.insert(h, k.clone());
        k
    }

    fn expr_uncached(&mut self, frame: &mut Frame<'_>, h: Handle<Expression>) -> Kind {
        let all = |a: &mut Self, frame: &mut Frame<'_>, hs: &[Handle<Expression>]| {
            hs.iter()
                .fold(Kind::Const, |k, &e| k.join(a.expr(frame, e)))
        };
        match &frame.function.expressions[h] {
            Expression::Literal(_)
            | Expression::Constant(_)
            | Expression::Override(_)
            | Expression::ZeroValue(_) => Kind::Const,
            Expression::Compose { components, .. } => {
                let c = components.clone();
                all(self, frame, &c)
            }
            Expression::Access { base, index } => {
                let (b, i) = (*base, *index);
                match (self.expr(frame, b), self.expr(frame, i)) {
                    (Kind::Place(p), Kind::Const) => Kind::Place(format!("{p}.[c]")),
                    (kb, ki) => kb.join(ki),
                }
            }
            Expression::AccessIndex { base, index } => {
                let (b, i) = (*base, *index);
                match self.expr(frame, b) {
                    Kind::Place(p) => Kind::Place(format!("{p}.{i}")),
                    k => k,
                }
            }
            Expression::Splat { value, .. } => {
                let v = *value;
                self.expr(frame, v).value()
            }
            Expression::Swizzle { vector, .. } => {
                let v = *vector;
                self.expr(frame, v).value()
            }
            Expression::FunctionArgument(i) => frame
                .args
                .get(*i as usize)
                .cloned()
                .unwrap_or(Kind::Varying),
            Expression::Load { pointer } => {
                let p = *pointer;
                match self.place(frame, p) {
                    Place::Uniform(name, Some(path)) => {
                        let mut s = name;
                        for i in path {
                            if i == u32::MAX {
                                s.push_str(".[c]");
                            } else {
                                s.push_str(&format!(".{i}"));
                            }
                        }
                        Kind::Place(s)
                    }
                    Place::Local(v) => frame.locals.get(&v).cloned().unwrap_or(Kind::Varying),
                    _ => Kind::Varying,
                }
            }
            Expression::Unary { expr, .. } => {
                let e = *expr;
                self.expr(frame, e).value()
            }
            Expression::Binary { left, right, .. } => {
                let (l, r) = (*left, *right);
                all(self, frame, &[l, r])
            }
            Expression::Select {
                condition,
                accept,
                reject,
            } => {
                let (c, a, r) = (*condition, *accept, *reject);
                all(self, frame, &[c, a, r])
            }
            Expression::Relational { argument, .. } => {
                let a = *argument;
                self.expr(frame, a).value()
            }
            Expression::Math {
                arg,
                arg1,
                arg2,
                arg3,
                ..
            } => {
                let hs: Vec<_> = [Some(*arg), *arg1, *arg2, *arg3]
                    .into_iter()
                    .flatten()
                    .collect();
                all(self, frame, &hs)
            }
            Expression::As { expr, .. } => {
                let e = *expr;
                self.expr(frame, e).value()
            }
            Expression::CallResult(f) => {
                let f = *f;
                // The call statement that produced it: find its arguments.
                let args = find_call(&frame.function.body, h).unwrap_or_default();
                let kinds = args.iter().map(|&a| self.expr(frame, a)).collect();
                self.call(f, kinds)
            }
            // Pointers as values (to locals, globals): their loads are what counts.
            Expression::GlobalVariable(_) | Expression::LocalVariable(_) => Kind::Varying,
            _ => Kind::Varying,
        }
    }
}

/// `h` written out, `depth` levels deep.
fn write(function: &Function, h: Handle<Expression>, depth: u32) -> String {
    if depth == 0 {
        return "..".into();
    }
    let w = |e| write(function, e, depth - 1);
    match &function.expressions[h] {
        Expression::Literal(l) => format!("{l:?}"),
        Expression::Constant(_) | Expression::Override(_) => "const".into(),
        Expression::ZeroValue(_) => "0".into(),
        Expression::AccessIndex { base, index } => format!("{}.{index}", w(*base)),
        Expression::Access { base, index } => format!("{}[{}]", w(*base), w(*index)),
        Expression::Load { pointer } => w(*pointer),
        Expression::GlobalVariable(g) => function_global_name(g),
        Expression::LocalVariable(v) => function.local_variables[*v]
            .name
            .clone()
            .unwrap_or_else(|| "local".into()),
        Expression::FunctionArgument(i) => format!("arg{i}"),
        Expression::Unary { op, expr } => format!("{op:?}({})", w(*expr)),
        Expression::Binary { op, left, right } => format!("({} {op:?} {})", w(*left), w(*right)),
        Expression::As { expr, .. } => w(*expr),
        e => format!("{e:?}")
            .split([' ', '(', '{'])
            .next()
            .unwrap_or("?")
            .to_owned(),
    }
}

fn function_global_name(g: &Handle<naga::GlobalVariable>) -> String {
    format!("global{}", g.index())
}

/// The arguments of the call whose result is `result`.
fn find_call(block: &Block, result: Handle<Expression>) -> Option<Vec<Handle<Expression>>> {
    for stmt in block.iter() {
        let found = match stmt {
            Statement::Call {
                arguments,
                result: Some(r),
                ..
            } if *r == result => Some(arguments.clone()),
            Statement::Block(b) => find_call(b, result),
            Statement::If { accept, reject, .. } => {
                find_call(accept, result).or_else(|| find_call(reject, result))
            }
            Statement::Switch { cases, .. } => {
                cases.iter().find_map(|c| find_call(&c.body, result))
            }
            Statement::Loop {
                body, continuing, ..
            } => find_call(body, result).or_else(|| find_call(continuing, result)),
            _ => None,
        };
        if found.is_some() {
            return found;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn branches(src: &str) -> Vec<UniformBranch> {
        let module = naga::front::wgsl::parse_str(src).expect("test WGSL parses");
        uniform_branches(&module, "main")
    }

    const HEADER: &str = "struct F { n: u32, k: vec4<u32> }\n\
        @group(0) @binding(0) var<uniform> f: F;\n\
        @group(0) @binding(1) var<storage, read_write> out: array<u32>;\n";

    #[test]
    fn a_uniform_if_is_found_and_a_select_is_not() {
        let found = branches(&format!(
            "{HEADER}@compute @workgroup_size(8) fn main(@builtin(global_invocation_id) id: vec3<u32>) {{\n\
             var u = 1u; if f.k[2] != 0u {{ u = 2u; }} out[id.x] = u; }}"
        ));
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].statement, "if");
        assert_eq!(found[0].reads, vec!["f.1.2".to_owned()]);
        let found = branches(&format!(
            "{HEADER}@compute @workgroup_size(8) fn main(@builtin(global_invocation_id) id: vec3<u32>) {{\n\
             out[id.x] = select(1u, 2u, f.k[2] != 0u); }}"
        ));
        assert!(found.is_empty(), "{found:?}");
    }

    #[test]
    fn a_loop_bounded_by_a_uniform_is_found_unless_it_starts_per_invocation() {
        let found = branches(&format!(
            "{HEADER}@compute @workgroup_size(8) fn main(@builtin(global_invocation_id) id: vec3<u32>) {{\n\
             var s = 0u; for (var i = 0u; i < f.n; i++) {{ s += i; }} out[id.x] = s; }}"
        ));
        assert_eq!(found.len(), 1, "{found:?}");
        let found = branches(&format!(
            "{HEADER}@compute @workgroup_size(8) fn main(@builtin(global_invocation_id) id: vec3<u32>) {{\n\
             var s = 0u; for (var i = id.x % 4u; i < f.n; i++) {{ s += i; }} out[id.x] = s; }}"
        ));
        assert!(found.is_empty(), "{found:?}");
    }

    #[test]
    fn uniform_arguments_are_followed_into_callees() {
        let found = branches(&format!(
            "{HEADER}fn pick(a: u32, b: u32) -> u32 {{ if a > 3u {{ return b; }} return 0u; }}\n\
             @compute @workgroup_size(8) fn main(@builtin(global_invocation_id) id: vec3<u32>) {{\n\
             out[id.x] = pick(id.x, 1u) + pick(f.n, id.x); }}"
        ));
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].function, "pick");
        let found = branches(&format!(
            "{HEADER}fn pick(a: u32, b: u32) -> u32 {{ if a > 3u {{ return b; }} return 0u; }}\n\
             @compute @workgroup_size(8) fn main(@builtin(global_invocation_id) id: vec3<u32>) {{\n\
             out[id.x] = pick(id.x, f.n); }}"
        ));
        assert!(found.is_empty(), "{found:?}");
    }

    #[test]
    fn storage_and_dynamic_indices_are_not_uniform() {
        let found = branches(&format!(
            "{HEADER}@compute @workgroup_size(8) fn main(@builtin(global_invocation_id) id: vec3<u32>) {{\n\
             var u = 1u; if out[0] != 0u {{ u = 2u; }} if f.k[id.x % 4u] != 0u {{ u = 3u; }} out[id.x] = u; }}"
        ));
        assert!(found.is_empty(), "{found:?}");
    }

    #[test]
    fn a_local_given_two_values_is_not_uniform_unless_a_loop_counter_tests_it() {
        // A phi: lavapipe does not follow it.
        let found = branches(&format!(
            "{HEADER}@compute @workgroup_size(8) fn main(@builtin(global_invocation_id) id: vec3<u32>) {{\n\
             var u = 1u; if id.x > 3u {{ u = f.n; }} var s = 0u; if u > 2u {{ s = 1u; }} out[id.x] = s; }}"
        ));
        assert!(found.is_empty(), "{found:?}");
        // An exit test that is not `counter <op> uniform` (lavapipe: `i + 1 < n` is not).
        let found = branches(&format!(
            "{HEADER}@compute @workgroup_size(8) fn main(@builtin(global_invocation_id) id: vec3<u32>) {{\n\
             var s = 0u; for (var i = 0u; i + 1u < f.n; i++) {{ s += i; }} out[id.x] = s; }}"
        ));
        assert!(found.is_empty(), "{found:?}");
    }

    #[test]
    fn a_condition_reading_more_than_four_uniform_words_is_left_alone() {
        // f.k (4 words) and f.n: lavapipe inlines at most 4.
        let found = branches(&format!(
            "{HEADER}@compute @workgroup_size(8) fn main(@builtin(global_invocation_id) id: vec3<u32>) {{\n\
             var u = 1u; if dot(vec4<f32>(f.k), vec4<f32>(1.0)) > f32(f.n) {{ u = 2u; }} out[id.x] = u; }}"
        ));
        assert!(found.is_empty(), "{found:?}");
    }
}
