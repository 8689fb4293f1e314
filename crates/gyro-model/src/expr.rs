//! Relations between coordinates, as a design file writes them: `theta + (zeta - xi)*(alpha - rho_rad)`.
//!
//! A hinge angle, a servo relation or a force's lever is a polynomial of degree ≤ 2 in the
//! generalised coordinates (this covers every contact and servo relation of the reference texts,
//! e.g. Beghin's roller contact φ − θ = (ζ − ξ)(α − ρ)). Keeping them polynomial lets the engine
//! evaluate them and their exact gradients on dual numbers without a general symbolic system.
//! Named parameters (constants of the design) may appear anywhere; `pi` is predefined, and
//! `deg(x)` converts degrees to radians; `sqrt`, `sin`, `cos`, `abs` apply to constants; `g`,
//! `earth_rate` and `earth_radius` are the constants of `constants`.

use crate::dual::Real;
use std::collections::BTreeMap;

/// c + Σ aᵢ qᵢ + Σ bᵢⱼ qᵢ qⱼ over coordinate indices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct QuadExpr {
    pub constant: f64,
    pub linear: Vec<(usize, f64)>,
    pub quadratic: Vec<(usize, usize, f64)>,
}

impl QuadExpr {
    pub fn constant(c: f64) -> Self {
        QuadExpr {
            constant: c,
            ..Default::default()
        }
    }
    pub fn coordinate(i: usize) -> Self {
        QuadExpr {
            linear: vec![(i, 1.0)],
            ..Default::default()
        }
    }
    pub fn is_constant(&self) -> bool {
        self.linear.is_empty() && self.quadratic.is_empty()
    }
    pub fn is_linear(&self) -> bool {
        self.quadratic.is_empty()
    }
    /// Every coordinate index the expression reads.
    pub fn coordinates(&self) -> Vec<usize> {
        let mut v: Vec<usize> = self.linear.iter().map(|l| l.0).collect();
        for &(i, j, _) in &self.quadratic {
            v.push(i);
            v.push(j);
        }
        v.sort_unstable();
        v.dedup();
        v
    }
    pub fn eval<T: Real>(&self, q: &[T]) -> T {
        let mut s = T::cst(self.constant);
        for &(i, a) in &self.linear {
            s += q[i] * a;
        }
        for &(i, j, b) in &self.quadratic {
            s += q[i] * q[j] * b;
        }
        s
    }
    /// Adds ∂E/∂q_k into `grad[k]` (exact: the gradient of a quadratic is linear).
    pub fn add_gradient<T: Real>(&self, q: &[T], grad: &mut [T]) {
        for &(i, a) in &self.linear {
            grad[i] += T::cst(a);
        }
        for &(i, j, b) in &self.quadratic {
            grad[i] += q[j] * b;
            grad[j] += q[i] * b;
        }
    }
    /// The constant second derivative matrix entries (for qᵀ∇²E q terms).
    pub fn hessian_quadratic_form(&self, v: &[f64]) -> f64 {
        self.quadratic
            .iter()
            .map(|&(i, j, b)| 2.0 * b * v[i] * v[j])
            .sum()
    }

    fn add(mut self, o: QuadExpr) -> QuadExpr {
        self.constant += o.constant;
        self.linear.extend(o.linear);
        self.quadratic.extend(o.quadratic);
        self.simplify()
    }
    fn scale(mut self, s: f64) -> QuadExpr {
        self.constant *= s;
        for l in &mut self.linear {
            l.1 *= s;
        }
        for q in &mut self.quadratic {
            q.2 *= s;
        }
        self
    }
    fn mul(self, o: QuadExpr) -> Result<QuadExpr, String> {
        if self.is_constant() {
            return Ok(o.scale(self.constant));
        }
        if o.is_constant() {
            return Ok(self.scale(o.constant));
        }
        if !self.quadratic.is_empty() || !o.quadratic.is_empty() {
            return Err("product of degree above 2 (relations must be at most quadratic)".into());
        }
        let mut r = QuadExpr::constant(self.constant * o.constant);
        for &(i, a) in &self.linear {
            r.linear.push((i, a * o.constant));
        }
        for &(j, b) in &o.linear {
            r.linear.push((j, b * self.constant));
        }
        for &(i, a) in &self.linear {
            for &(j, b) in &o.linear {
                r.quadratic.push((i.min(j), i.max(j), a * b));
            }
        }
        Ok(r.simplify())
    }
    fn simplify(mut self) -> QuadExpr {
        let mut lin: BTreeMap<usize, f64> = BTreeMap::new();
        for (i, a) in self.linear.drain(..) {
            *lin.entry(i).or_default() += a;
        }
        let mut quad: BTreeMap<(usize, usize), f64> = BTreeMap::new();
        for (i, j, b) in self.quadratic.drain(..) {
            *quad.entry((i.min(j), i.max(j))).or_default() += b;
        }
        self.linear = lin.into_iter().filter(|x| x.1 != 0.0).collect();
        self.quadratic = quad
            .into_iter()
            .filter(|x| x.1 != 0.0)
            .map(|((i, j), b)| (i, j, b))
            .collect();
        self
    }
}

/// Parses `text` with coordinate names (→ indices) and named parameters (→ values).
pub fn parse(
    text: &str,
    coordinates: &[String],
    parameters: &BTreeMap<String, f64>,
) -> Result<QuadExpr, String> {
    let tokens = tokenize(text)?;
    let mut p = Parser {
        tokens,
        pos: 0,
        coordinates,
        parameters,
    };
    let e = p.sum()?;
    if p.pos != p.tokens.len() {
        return Err(format!(
            "unexpected `{}` in `{text}`",
            p.tokens[p.pos].show()
        ));
    }
    Ok(e)
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(f64),
    Ident(String),
    Op(char),
}
impl Tok {
    fn show(&self) -> String {
        match self {
            Tok::Num(x) => x.to_string(),
            Tok::Ident(s) => s.clone(),
            Tok::Op(c) => c.to_string(),
        }
    }
}

fn tokenize(s: &str) -> Result<Vec<Tok>, String> {
    let chars: Vec<char> = s.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_digit() || c == '.' {
            let start = i;
            while i < chars.len()
                && (chars[i].is_ascii_digit()
                    || chars[i] == '.'
                    || chars[i] == 'e'
                    || chars[i] == 'E'
                    || ((chars[i] == '-' || chars[i] == '+')
                        && i > start
                        && (chars[i - 1] == 'e' || chars[i - 1] == 'E')))
            {
                i += 1;
            }
            let t: String = chars[start..i].iter().collect();
            out.push(Tok::Num(
                t.parse().map_err(|_| format!("bad number `{t}`"))?,
            ));
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push(Tok::Ident(chars[start..i].iter().collect()));
        } else if "+-*/()".contains(c) {
            out.push(Tok::Op(c));
            i += 1;
        } else {
            return Err(format!(
                "unexpected character `{c}` (allowed: numbers, names, + - * / ( ))"
            ));
        }
    }
    Ok(out)
}

/// Constants every expression may use (shadowed by coordinates and parameters of the same name).
pub fn builtin(name: &str) -> Option<f64> {
    use crate::constants::*;
    Some(match name {
        "pi" => std::f64::consts::PI,
        "g" => STANDARD_GRAVITY_M_PER_S2,
        "earth_rate" => EARTH_RATE_RAD_PER_S,
        "earth_radius" => EARTH_RADIUS_M,
        _ => return None,
    })
}

struct Parser<'a> {
    tokens: Vec<Tok>,
    pos: usize,
    coordinates: &'a [String],
    parameters: &'a BTreeMap<String, f64>,
}

impl Parser<'_> {
    fn peek(&self) -> Option<&Tok> {
        self.tokens.get(self.pos)
    }
    fn sum(&mut self) -> Result<QuadExpr, String> {
        let mut e = self.product()?;
        while let Some(Tok::Op(c @ ('+' | '-'))) = self.peek().cloned() {
            self.pos += 1;
            let r = self.product()?;
            e = e.add(if c == '+' { r } else { r.scale(-1.0) });
        }
        Ok(e)
    }
    fn product(&mut self) -> Result<QuadExpr, String> {
        let mut e = self.unary()?;
        while let Some(Tok::Op(c @ ('*' | '/'))) = self.peek().cloned() {
            self.pos += 1;
            let r = self.unary()?;
            e = if c == '*' {
                e.mul(r)?
            } else {
                if !r.is_constant() || r.constant == 0.0 {
                    return Err("division only by a non-zero constant".into());
                }
                e.scale(1.0 / r.constant)
            };
        }
        Ok(e)
    }
    fn unary(&mut self) -> Result<QuadExpr, String> {
        match self.peek().cloned() {
            Some(Tok::Op('-')) => {
                self.pos += 1;
                Ok(self.unary()?.scale(-1.0))
            }
            Some(Tok::Op('+')) => {
                self.pos += 1;
                self.unary()
            }
            _ => self.atom(),
        }
    }
    fn atom(&mut self) -> Result<QuadExpr, String> {
        let t = self.peek().cloned().ok_or("expression ends too early")?;
        self.pos += 1;
        match t {
            Tok::Num(x) => Ok(QuadExpr::constant(x)),
            Tok::Op('(') => {
                let e = self.sum()?;
                if self.peek() != Some(&Tok::Op(')')) {
                    return Err("missing `)`".into());
                }
                self.pos += 1;
                Ok(e)
            }
            Tok::Ident(name) => {
                if matches!(name.as_str(), "deg" | "sin" | "cos" | "sqrt" | "abs") {
                    if self.peek() != Some(&Tok::Op('(')) {
                        return Err(format!("`{name}` needs an argument in parentheses"));
                    }
                    let arg = self.atom()?;
                    if !arg.is_constant() {
                        return Err(format!("`{name}(…)` takes constants only"));
                    }
                    let x = arg.constant;
                    if name == "sqrt" && x < 0.0 {
                        return Err(format!("sqrt of a negative number ({x})"));
                    }
                    return Ok(QuadExpr::constant(match name.as_str() {
                        "deg" => x.to_radians(),
                        "sin" => x.sin(),
                        "cos" => x.cos(),
                        "sqrt" => x.sqrt(),
                        _ => x.abs(),
                    }));
                }
                if let Some(i) = self.coordinates.iter().position(|c| *c == name) {
                    return Ok(QuadExpr::coordinate(i));
                }
                if let Some(v) = self.parameters.get(&name) {
                    return Ok(QuadExpr::constant(*v));
                }
                if let Some(v) = builtin(&name) {
                    return Ok(QuadExpr::constant(v));
                }
                Err(format!(
                    "unknown name `{name}` (coordinates: {}; parameters: {})",
                    self.coordinates.join(", "),
                    self.parameters
                        .keys()
                        .cloned()
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            }
            Tok::Op(c) => Err(format!("unexpected `{c}`")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roller_contact_relation_parses_to_its_polynomial() {
        let coords: Vec<String> = ["theta", "zeta", "xi", "alpha"].map(String::from).to_vec();
        let mut params = BTreeMap::new();
        params.insert("rho_rad".to_string(), 0.035);
        let e = parse("theta + (zeta - xi)*(alpha - rho_rad)", &coords, &params).expect("parses");
        let q = [0.1, 0.2, 0.15, -0.3];
        let direct = 0.1 + (0.2 - 0.15) * (-0.3 - 0.035);
        assert!((e.eval(&q) - direct).abs() < 1e-15);
        let mut g = [0.0; 4];
        e.add_gradient(&q, &mut g);
        assert!((g[0] - 1.0).abs() < 1e-15);
        assert!((g[1] - (-0.3 - 0.035)).abs() < 1e-15);
        assert!((g[2] + (-0.3 - 0.035)).abs() < 1e-15);
        assert!((g[3] - (0.2 - 0.15)).abs() < 1e-15);
    }

    #[test]
    fn cubic_terms_and_unknown_names_are_refused() {
        let coords: Vec<String> = vec!["a".into()];
        let p = BTreeMap::new();
        assert!(parse("a*a*a", &coords, &p).is_err());
        assert!(
            parse("a + b", &coords, &p)
                .err()
                .is_some_and(|e| e.contains("unknown name `b`"))
        );
        assert!(parse("deg(90) - a", &coords, &p).is_ok());
    }
}
