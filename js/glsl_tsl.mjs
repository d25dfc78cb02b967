// glsl_tsl.mjs -- the GLSL -> TSL emitter of js/build.mjs: glsl/*.glsl (the one source of the maths) becomes
// three.js node functions (TSL) for WebGPURenderer, so no formula is written twice by hand.
//
// Why an emitter of our own and not three's transpiler (examples/jsm/transpiler, r187): that one writes
// an `out` parameter into a copy the caller never sees (every axial_* function returns through them),
// and makes each function a WGSL function of its own through Fn() layouts and struct() types, which the
// oldest three the WebGPU entry supports (r184) does not all take.  This one inlines every call into the
// caller's graph, exactly as a hand port does, so what it writes uses only vector nodes, If/Loop and
// select -- the TSL every supported three has.
//
// The GLSL it takes (an error names the line of anything else):
// - structs (a value is a JavaScript object of nodes; a struct's `bool` fields are STATIC: plain
//   JavaScript booleans that choose the code, as a specialization constant does), `const` scalars,
//   functions (overloads get the parameter types in their JavaScript name), `in`/`out`/`inout`;
// - locals (each a node variable), arrays of a constant length (JavaScript arrays of variables, indexed
//   by static numbers), mat3 (lowered to three column vectors);
// - if/else (a static condition chooses in JavaScript, a dynamic one becomes If/Else), for loops with
//   constant bounds (unrolled in JavaScript) or with a break (a TSL Loop), return anywhere (early
//   returns become a result variable), the ternary (select), every operator of GLSL on scalars and vectors;
// - function declarations without a body: hooks, what the program gives the source (its storage); a call to
//   one is `hooks.<name>(...)`, `hooks` the last parameter of every emitted function that reaches a hook;
// - #ifdef/#ifndef/#else/#endif with the defines it is given; around statements, those of a `switch` (a define the
//   program chooses as it builds its nodes) become a static if of the runtime's `switches.<NAME>`, so both
//   builds are in the module and the one a mesh needs is the one its graph gets.
// Static values are literals, `const`s, unrolled loop indices and static struct fields; everything else
// is a node.  A static that meets a node becomes a node of its own GLSL type (float/int/uint/bool).

const TYPES = new Set(['void', 'float', 'int', 'uint', 'bool', 'vec2', 'vec3', 'vec4', 'ivec2', 'ivec3', 'ivec4',
  'uvec2', 'uvec3', 'uvec4', 'bvec2', 'bvec3', 'bvec4', 'mat3', 'sampler2D']);
const SCALAR_CTOR = { float: 'float', int: 'int', uint: 'uint', bool: 'bool' };
const ABBREV = { float: 'f', int: 'i', uint: 'u', bool: 'b', vec2: 'v2', vec3: 'v3', vec4: 'v4', ivec2: 'iv2', ivec3: 'iv3',
  ivec4: 'iv4', uvec2: 'uv2', uvec3: 'uv3', uvec4: 'uv4', mat3: 'm3', sampler2D: 's' };
const METHOD = { '+': 'add', '-': 'sub', '*': 'mul', '/': 'div', '%': 'mod', '==': 'equal', '!=': 'notEqual', '<': 'lessThan',
  '>': 'greaterThan', '<=': 'lessThanEqual', '>=': 'greaterThanEqual', '&&': 'and', '||': 'or', '^': 'bitXor',
  '&': 'bitAnd', '|': 'bitOr', '>>': 'shiftRight', '<<': 'shiftLeft' };
const ASSIGN = { '=': 'assign', '+=': 'addAssign', '-=': 'subAssign', '*=': 'mulAssign', '/=': 'divAssign' };
const PREC = [['||'], ['&&'], ['|'], ['^'], ['&'], ['==', '!='], ['<', '>', '<=', '>='], ['<<', '>>'], ['+', '-'], ['*', '/', '%']];
// builtins: TSL name, and the result type from the argument types
const same = (t) => t[0];
const BUILTINS = {
  floor: ['floor', same], abs: ['abs', same], sqrt: ['sqrt', same], inversesqrt: ['inverseSqrt', same], fract: ['fract', same],
  sign: ['sign', same], exp: ['exp', same], log: ['log', same], exp2: ['exp2', same], log2: ['log2', same],
  clamp: ['clamp', same], min: ['min', same], max: ['max', same], mix: ['mix', same], step: ['step', (t) => t[1]],
  smoothstep: ['smoothstep', (t) => t[2]], pow: ['pow', same], normalize: ['normalize', same], round: ['round', same],
  dot: ['dot', (t) => base(t[0])], length: ['length', (t) => base(t[0])], distance: ['distance', (t) => base(t[0])],
  cross: ['cross', () => 'vec3'], all: ['all', () => 'bool'], any: ['any', () => 'bool'],
  floatBitsToUint: ['floatBitsToUint', (t) => (t[0] === 'float' ? 'uint' : 'u' + t[0])],
  uintBitsToFloat: ['uintBitsToFloat', (t) => (t[0] === 'uint' ? 'float' : t[0].slice(1))],
};
const COMPARE = { lessThan: 'lessThan', lessThanEqual: 'lessThanEqual', greaterThan: 'greaterThan',
  greaterThanEqual: 'greaterThanEqual', equal: 'equal', notEqual: 'notEqual' };

function size(t) { return /\d$/.test(t) ? Number(t.slice(-1)) : 1; }
function base(t) {
  if (t.startsWith('ivec')) return 'int';
  if (t.startsWith('uvec')) return 'uint';
  if (t.startsWith('bvec')) return 'bool';
  return t.startsWith('vec') || t === 'mat3' ? 'float' : t;
}
function vecOf(b, n) {
  if (n === 1) return b;
  return { float: 'vec', int: 'ivec', uint: 'uvec', bool: 'bvec' }[b] + n;
}
const camel = (s) => s.replace(/_([a-z0-9])/g, (_, c) => c.toUpperCase());

class GlslError extends Error {}

// ---------------------------------------------------------------- preprocessing and tokens
function preprocess(text, defines, where, switches = []) {
  const out = [];
  const stack = []; // [active, taken, a switch]
  const active = () => stack.every((s) => s[0]);
  text.split('\n').forEach((line, n) => {
    const m = /^\s*#\s*(\w+)\s*(.*)$/.exec(line);
    if (!m) { out.push(active() ? line : ''); return; }
    const [, dir, rest] = m;
    const name = rest.trim().split(/\s+/)[0];
    const top = stack[stack.length - 1];
    if ((dir === 'ifdef' || dir === 'ifndef') && switches.includes(name)) { // kept: a static if of the switch
      stack.push([true, true, true]);
      out.push(active() ? `if (${dir === 'ifdef' ? '' : '!'}${name}) {` : '');
      return;
    }
    if (top && top[2] && (dir === 'else' || dir === 'endif')) {
      if (dir === 'endif') stack.pop();
      out.push(active() ? (dir === 'else' ? '} else {' : '}') : '');
      return;
    }
    if (dir === 'ifdef' || dir === 'ifndef') {
      const on = (name in defines) === (dir === 'ifdef');
      stack.push([on, on, false]);
    } else if (dir === 'else') {
      top[0] = !top[1];
    } else if (dir === 'endif') {
      stack.pop();
    } else if (dir === 'define' || dir === 'include' || dir === 'version') {
      if (active()) throw new GlslError(`${where}:${n + 1}: #${dir} is not in the subset the emitter takes`);
    } else {
      throw new GlslError(`${where}:${n + 1}: #${dir} is not in the subset the emitter takes (#ifdef, #ifndef, #else, #endif)`);
    }
    out.push('');
  });
  return out.join('\n');
}

const TOKEN = /\s+|\/\/[^\n]*|\/\*[\s\S]*?\*\/|(\d+\.\d*(?:[eE][+-]?\d+)?|\.\d+(?:[eE][+-]?\d+)?|\d+[eE][+-]?\d+|\d+u?)|([A-Za-z_]\w*)|(<<=|>>=|\+\+|--|&&|\|\||==|!=|<=|>=|<<|>>|\+=|-=|\*=|\/=|%=|[-+*/%<>=!?:;,.(){}[\]^&|~])/y;

function tokenize(text, where) {
  const tokens = [];
  let line = 1;
  TOKEN.lastIndex = 0;
  while (TOKEN.lastIndex < text.length) {
    const at = TOKEN.lastIndex;
    const m = TOKEN.exec(text);
    if (!m) throw new GlslError(`${where}:${line}: cannot read ${JSON.stringify(text.slice(at, at + 20))}`);
    if (m[1]) tokens.push({ t: 'num', v: m[1], line });
    else if (m[2]) tokens.push({ t: 'id', v: m[2], line });
    else if (m[3]) tokens.push({ t: 'op', v: m[3], line });
    else if (m[0].startsWith('//')) tokens.push({ t: 'comment', v: m[0].slice(2).replace(/^ /, ''), line });
    line += (m[0].match(/\n/g) || []).length;
  }
  return tokens;
}

// ---------------------------------------------------------------- parsing
class Parser {
  constructor(tokens, where) {
    this.all = tokens;
    this.toks = tokens.filter((t) => t.t !== 'comment');
    this.i = 0;
    this.where = where;
    this.structs = new Map();
  }

  peek(k = 0) { return this.toks[this.i + k] || { t: 'eof', v: '', line: -1 }; }
  fail(msg, tok = this.peek()) { throw new GlslError(`${this.where}:${tok.line}: ${msg}`); }
  next() { return this.toks[this.i++]; }
  is(v, k = 0) { const t = this.peek(k); return t.t !== 'num' && t.v === v; }
  eat(v) {
    if (!this.is(v)) this.fail(`expected "${v}", found "${this.peek().v}"`);
    return this.next();
  }
  ident() {
    const t = this.next();
    if (!t || t.t !== 'id') this.fail('expected a name', t);
    return t.v;
  }
  isType(k = 0) { const t = this.peek(k); return t.t === 'id' && (TYPES.has(t.v) || this.structs.has(t.v)); }

  // the comment lines right above line `line`
  commentAbove(line) {
    const lines = [];
    for (let n = line - 1; ; n--) {
      const c = this.all.find((t) => t.t === 'comment' && t.line === n);
      if (!c || this.all.some((t) => t.t !== 'comment' && t.line === n)) break;
      lines.unshift(c.v);
    }
    return lines;
  }

  program() {
    const items = [];
    while (this.peek().t !== 'eof') {
      const line = this.peek().line;
      if (this.is('struct')) {
        this.next();
        const name = this.ident();
        this.eat('{');
        const fields = [];
        while (!this.is('}')) {
          const type = this.ident();
          do fields.push({ type, name: this.ident() }); while (this.is(',') && this.next());
          this.eat(';');
        }
        this.eat('}');
        this.eat(';');
        this.structs.set(name, fields);
        items.push({ kind: 'struct', name, fields });
      } else if (this.is('const')) {
        this.next();
        const type = this.ident();
        const name = this.ident();
        this.eat('=');
        const value = this.expr();
        this.eat(';');
        items.push({ kind: 'const', type, name, value, line });
      } else {
        if (!this.isType()) this.fail(`expected a struct, a const or a function, found "${this.peek().v}"`);
        const ret = this.ident();
        const name = this.ident();
        this.eat('(');
        const params = [];
        while (!this.is(')')) {
          let qual = 'in';
          if (this.is('in') || this.is('out') || this.is('inout')) qual = this.next().v;
          const type = this.ident();
          const pname = this.ident();
          let arr = null;
          if (this.is('[')) { this.next(); arr = this.expr(); this.eat(']'); }
          params.push({ qual, type, name: pname, arr });
          if (this.is(',')) this.next();
        }
        this.eat(')');
        if (this.is(';')) { this.next(); items.push({ kind: 'proto', ret, name, params, line }); continue; }
        items.push({ kind: 'func', ret, name, params, body: this.block(), line, doc: this.commentAbove(line) });
      }
    }
    return items;
  }

  block() {
    this.eat('{');
    const body = [];
    while (!this.is('}')) body.push(this.statement());
    this.eat('}');
    return body;
  }

  statement() {
    const line = this.peek().line;
    if (this.is('{')) return { k: 'block', body: this.block(), line };
    if (this.is('if')) {
      this.next(); this.eat('(');
      const c = this.expr();
      this.eat(')');
      const t = this.statement();
      let f = null;
      if (this.is('else')) { this.next(); f = this.statement(); }
      return { k: 'if', c, t, f, line };
    }
    if (this.is('for')) {
      this.next(); this.eat('(');
      const init = this.statement();
      const cond = this.expr();
      this.eat(';');
      const step = this.expr();
      this.eat(')');
      return { k: 'for', init, cond, step, body: this.statement(), line };
    }
    if (this.is('return')) {
      this.next();
      const e = this.is(';') ? null : this.expr();
      this.eat(';');
      return { k: 'ret', e, line };
    }
    if (this.is('break')) { this.next(); this.eat(';'); return { k: 'break', line }; }
    if (this.is('const') && this.isType(1)) this.next();
    if (this.isType() && this.peek(1).t === 'id') {
      const type = this.ident();
      const vars = [];
      do {
        const name = this.ident();
        let arr = null, init = null;
        if (this.is('[')) { this.next(); arr = this.expr(); this.eat(']'); }
        if (this.is('=')) { this.next(); init = this.assign(); }
        vars.push({ name, arr, init });
      } while (this.is(',') && this.next());
      this.eat(';');
      return { k: 'decl', type, vars, line };
    }
    const e = this.expr();
    this.eat(';');
    return { k: 'expr', e, line };
  }

  expr() { return this.assign(); }

  assign() {
    const a = this.ternary();
    const t = this.peek();
    if (t.t === 'op' && ['=', '+=', '-=', '*=', '/='].includes(t.v)) {
      this.next();
      return { k: 'assign', op: t.v, a, b: this.assign(), line: t.line };
    }
    return a;
  }

  ternary() {
    const c = this.binary(0);
    if (!this.is('?')) return c;
    const line = this.next().line;
    const a = this.assign();
    this.eat(':');
    return { k: 'tern', c, a, b: this.assign(), line };
  }

  binary(level) {
    if (level === PREC.length) return this.unary();
    let a = this.binary(level + 1);
    while (this.peek().t === 'op' && PREC[level].includes(this.peek().v)) {
      const op = this.next();
      a = { k: 'bin', op: op.v, a, b: this.binary(level + 1), line: op.line };
    }
    return a;
  }

  unary() {
    const t = this.peek();
    if (t.t === 'op' && ['-', '!', '+', '++', '--'].includes(t.v)) {
      this.next();
      return { k: 'un', op: t.v, a: this.unary(), line: t.line };
    }
    return this.postfix();
  }

  postfix() {
    let e = this.primary();
    for (;;) {
      const t = this.peek();
      if (this.is('.')) { this.next(); e = { k: 'field', a: e, name: this.ident(), line: t.line }; }
      else if (this.is('[')) { this.next(); e = { k: 'index', a: e, i: this.expr(), line: t.line }; this.eat(']'); }
      else if (this.is('++') || this.is('--')) { this.next(); e = { k: 'un', op: t.v, a: e, line: t.line }; }
      else return e;
    }
  }

  primary() {
    const t = this.next();
    if (t.t === 'num') {
      const type = t.v.endsWith('u') ? 'uint' : /[.eE]/.test(t.v) ? 'float' : 'int';
      return { k: 'num', v: t.v.replace(/u$/, ''), type, line: t.line };
    }
    if (t.t === 'id') {
      if (t.v === 'true' || t.v === 'false') return { k: 'bool', v: t.v, line: t.line };
      if (this.is('(')) {
        this.next();
        const args = [];
        while (!this.is(')')) { args.push(this.assign()); if (this.is(',')) this.next(); }
        this.eat(')');
        return { k: 'call', name: t.v, args, line: t.line };
      }
      return { k: 'id', name: t.v, line: t.line };
    }
    if (t.v === '(') { const e = this.expr(); this.eat(')'); return e; }
    return this.fail(`unexpected "${t.v}"`, t);
  }
}

// ---------------------------------------------------------------- emitting
// A value while emitting: {code, type, stat (a JavaScript value, not a node), arr (a JavaScript array of
// `arr` elements), lv (assignable)}.
class Emitter {
  constructor(items, where) {
    this.where = where;
    this.structs = new Map(items.filter((x) => x.kind === 'struct').map((x) => [x.name, x.fields]));
    this.consts = new Map();
    this.funcs = new Map(); // name -> [func]
    for (const x of items) {
      if (x.kind === 'func' || x.kind === 'proto') {
        if (!this.funcs.has(x.name)) this.funcs.set(x.name, []);
        this.funcs.get(x.name).push(x);
      }
    }
    this.used = new Set();
    this.tmp = 0;
    // the functions that call a declared one (a hook), directly or through others: they take `hooks`
    const protos = items.filter((x) => x.kind === 'proto').map((x) => x.name);
    const bodies = items.filter((x) => x.kind === 'func');
    this.hooked = new Set(protos);
    for (let grew = true; grew;) {
      grew = false;
      for (const f of bodies) {
        if (!this.hooked.has(f.name) && [...calledNames(f.body)].some((n) => this.hooked.has(n))) {
          this.hooked.add(f.name);
          grew = true;
        }
      }
    }
    for (const n of protos) this.hooked.delete(n);
  }

  fail(msg, node) { throw new GlslError(`${this.where}:${node?.line ?? '?'}: ${msg}`); }

  jsName(f) {
    const all = this.funcs.get(f.name);
    if (all.length === 1) return camel(f.name);
    return camel(f.name) + '_' + f.params.map((p) => ABBREV[p.type] || p.type.replace(/[a-z]+/g, '')).join('');
  }

  tsl(name) { this.used.add(name); return name; }

  // a static value as a node of its GLSL type
  node(v, type = v.type) {
    if (!('stat' in v) || !v.stat) return v.code;
    const ctor = SCALAR_CTOR[type];
    if (!ctor) return v.code; // a vector or struct built of statics already is a node / an object
    return `${this.tsl(ctor)}(${v.code})`;
  }

  lookup(scope, name, where) {
    for (let s = scope; s; s = s.up) if (s.vars.has(name)) return s.vars.get(name);
    if (this.consts.has(name)) return this.consts.get(name);
    return this.fail(`"${name}" is not declared`, where);
  }

  // -------------------------------------------------------------- expressions
  expr(e, scope) {
    switch (e.k) {
      case 'num': return { code: e.v, type: e.type, stat: true };
      case 'bool': return { code: e.v, type: 'bool', stat: true };
      case 'id': {
        const v = this.lookup(scope, e.name, e);
        return { code: v.js, type: v.type, stat: !!v.stat, arr: v.arr, lv: !v.stat, mat: v.type === 'mat3' };
      }
      case 'field': return this.field(e, scope);
      case 'index': return this.index(e, scope);
      case 'call': return this.call(e, scope);
      case 'un': {
        const a = this.expr(e.a, scope);
        if (e.op === '++' || e.op === '--') this.fail('++ and -- only as a loop step or a statement', e);
        if (e.op === '+') return a;
        if (a.stat) return { code: `(${e.op}${a.code})`, type: a.type, stat: true };
        if (a.type === 'mat3') this.fail('a negated matrix', e);
        return { code: `${a.code}.${e.op === '-' ? 'negate' : 'not'}()`, type: a.type };
      }
      case 'bin': return this.binary(e, scope);
      case 'tern': {
        const c = this.expr(e.c, scope), a = this.expr(e.a, scope), b = this.expr(e.b, scope);
        if (a.type === 'mat3' || this.structs.has(a.type)) this.fail('a ternary of matrices or structs', e);
        if (c.stat && a.stat && b.stat) return { code: `(${c.code} ? ${a.code} : ${b.code})`, type: a.type, stat: true };
        if (c.stat) return { code: `(${c.code} ? ${this.node(a)} : ${this.node(b)})`, type: a.type };
        return { code: `${this.tsl('select')}(${c.code}, ${this.node(a)}, ${this.node(b)})`, type: a.type };
      }
      case 'assign': return this.fail('an assignment inside an expression', e);
      default: return this.fail(`cannot emit ${e.k}`, e);
    }
  }

  field(e, scope) {
    const a = this.expr(e.a, scope);
    const fields = this.structs.get(a.type);
    if (fields) {
      const f = fields.find((x) => x.name === e.name);
      if (!f) this.fail(`${a.type} has no field ${e.name}`, e);
      const stat = f.type === 'bool';
      return { code: `${a.code}.${e.name}`, type: f.type, stat, lv: !stat };
    }
    if (!/^[xyzw]{1,4}$/.test(e.name) && !/^[rgba]{1,4}$/.test(e.name)) this.fail(`.${e.name} of a ${a.type}`, e);
    if (a.stat) this.fail(`a swizzle of a static ${a.type}`, e);
    const name = e.name.replace(/[rgba]/g, (c) => 'xyzw'['rgba'.indexOf(c)]);
    return { code: `${a.code}.${name}`, type: vecOf(base(a.type), name.length), swz: { of: a, name }, lv: a.lv };
  }

  index(e, scope) {
    const a = this.expr(e.a, scope), i = this.expr(e.i, scope);
    if (a.arr) {
      if (!i.stat) this.fail('an array indexed by a node (only by static numbers: constants, unrolled loop indices)', e);
      const type = a.type;
      return { code: `${a.code}[${i.code}]`, type, lv: true, mat: type === 'mat3' };
    }
    if (a.type === 'mat3') {
      if (!i.stat) this.fail('a matrix column chosen by a node', e);
      return { code: `${a.code}[${i.code}]`, type: 'vec3', lv: a.lv, col: { of: a, i } };
    }
    const type = base(a.type);
    if (i.stat) {
      const lit = /^\d+$/.test(i.code) ? Number(i.code) : null;
      if (lit !== null) return { code: `${a.code}.${'xyzw'[lit]}`, type, swz: { of: a, name: 'xyzw'[lit] }, lv: a.lv };
      return { code: `${a.code}['xyzw'[${i.code}]]`, type, swz: { of: a, name: null, i }, lv: a.lv };
    }
    return { code: `${a.code}.element(${this.node(i)})`, type, swz: { of: a, name: null, i }, lv: a.lv };
  }

  binary(e, scope) {
    const a = this.expr(e.a, scope), b = this.expr(e.b, scope);
    const op = e.op;
    const cmp = ['==', '!=', '<', '>', '<=', '>='].includes(op);
    const logic = op === '&&' || op === '||';
    if (a.stat && b.stat) {
      const int = a.type === 'int' || a.type === 'uint';
      let code = `(${a.code} ${op === '^' ? '^' : op} ${b.code})`;
      if (op === '/' && int) code = `Math.trunc(${a.code} / ${b.code})`;
      if (op === '==' || op === '!=') code = `(${a.code} ${op}= ${b.code})`;
      return { code, type: cmp || logic ? 'bool' : a.type, stat: true };
    }
    if (logic && (a.stat || b.stat)) { // a static side decides in JavaScript
      const [s, d] = a.stat ? [a, b] : [b, a];
      const code = op === '&&' ? `(${s.code} ? ${d.code} : ${this.tsl('bool')}(false))`
        : `(${s.code} ? ${this.tsl('bool')}(true) : ${d.code})`;
      return { code, type: 'bool' };
    }
    if (a.type === 'mat3' || b.type === 'mat3') {
      if (op !== '*' && op !== '+' && op !== '-') this.fail(`${op} of a matrix`, e);
      if (op === '*' && a.type === 'mat3' && b.type === 'mat3') return { code: `${this.rt('matMul')}(${a.code}, ${b.code})`, type: 'mat3', mat: true };
      if (op === '*' && a.type === 'mat3' && size(b.type) === 3) return { code: `${this.rt('matVec')}(${a.code}, ${b.code})`, type: 'vec3' };
      if (op === '*' && a.type === 'mat3') return { code: `${this.rt('matScale')}(${a.code}, ${this.node(b)})`, type: 'mat3', mat: true };
      if (op === '*' && b.type === 'mat3' && size(a.type) === 1) return { code: `${this.rt('matScale')}(${b.code}, ${this.node(a)})`, type: 'mat3', mat: true };
      if (a.type === 'mat3' && b.type === 'mat3') return { code: `${this.rt(op === '+' ? 'matAdd' : 'matSub')}(${a.code}, ${b.code})`, type: 'mat3', mat: true };
      this.fail(`${a.type} ${op} ${b.type}`, e);
    }
    const type = cmp ? (size(a.type) > 1 ? vecOf('bool', size(a.type)) : 'bool') : logic ? 'bool'
      : size(a.type) >= size(b.type) ? a.type : b.type;
    if (cmp && size(a.type) > 1) this.fail(`${op} of vectors (use equal(), lessThan(), ... as GLSL says)`, e);
    return { code: `${this.node(a)}.${METHOD[op]}(${this.node(b, b.stat && size(a.type) === 1 ? a.type : b.type)})`, type };
  }

  rt(name) { this.runtime = this.runtime || new Set(); this.runtime.add(name); return name; }

  call(e, scope) {
    const name = e.name;
    const args = () => e.args.map((x) => this.expr(x, scope));
    if (TYPES.has(name)) return this.construct(name, args(), e);
    if (this.structs.has(name)) {
      const fields = this.structs.get(name), vals = args();
      if (vals.length !== fields.length) this.fail(`${name} takes ${fields.length} values`, e);
      const parts = fields.map((f, k) => `${f.name}: ${f.type === 'bool' ? vals[k].code : this.node(vals[k], f.type)}`);
      return { code: `{ ${parts.join(', ')} }`, type: name };
    }
    if (name === 'texelFetch') {
      const [tex, at] = args();
      return { code: `${this.rt('texelFetch')}(${tex.code}, ${at.code})`, type: 'vec4' };
    }
    if (name === 'transpose') {
      const [m] = args();
      return { code: `${this.rt('matTranspose')}(${m.code})`, type: 'mat3', mat: true };
    }
    if (name === 'outerProduct') {
      const [a, b] = args();
      return { code: `${this.rt('matOuter')}(${a.code}, ${b.code})`, type: 'mat3', mat: true };
    }
    if (COMPARE[name]) {
      const [a, b] = args();
      return { code: `${this.node(a)}.${COMPARE[name]}(${this.node(b)})`, type: vecOf('bool', size(a.type)) };
    }
    if (name === 'sin' || name === 'cos' || name === 'tan' || name === 'atan') {
      this.fail(`${name}(): the builtins' precision is each GPU's own; use the float32-accurate functions of the source`, e);
    }
    if (BUILTINS[name]) {
      const [fn, result] = BUILTINS[name];
      const vals = args();
      const first = vals.find((v) => !v.stat) || vals[0];
      const code = `${this.tsl(fn)}(${vals.map((v) => this.node(v, v.stat && size(first.type) === 1 ? first.type : v.type)).join(', ')})`;
      return { code, type: result(vals.map((v) => v.type)) };
    }
    const overloads = this.funcs.get(name);
    if (!overloads) this.fail(`${name}() is neither a function of the source nor a builtin the emitter knows`, e);
    const vals = args();
    const fits = overloads.filter((f) => f.params.length === vals.length
      && f.params.every((p, k) => p.type === vals[k].type || (vals[k].stat && SCALAR_CTOR[p.type] && SCALAR_CTOR[vals[k].type])));
    const exact = fits.filter((f) => f.params.every((p, k) => p.type === vals[k].type));
    const f = exact.length === 1 ? exact[0] : fits.length === 1 ? fits[0] : null;
    if (!f) this.fail(`no single ${name}() takes (${vals.map((v) => v.type).join(', ')})`, e);
    if (f.kind !== 'proto') this.need(f);
    const code = f.params.map((p, k) => {
      const v = vals[k];
      if (p.qual !== 'in') {
        if (!v.lv && !v.arr) this.fail(`the ${p.qual} argument ${k + 1} of ${name}() is not a variable`, e.args[k]);
        if (v.swz) this.fail(`the ${p.qual} argument ${k + 1} of ${name}() is a swizzle or a component`, e.args[k]);
        return v.code;
      }
      if (p.arr || p.type === 'mat3' || this.structs.has(p.type) || p.type === 'sampler2D') return v.code;
      return this.node(v, p.type);
    });
    // a declared function is a hook the caller gives (`hooks`, the last parameter of every function reaching one)
    if (f.kind === 'proto') return { code: `hooks.${camel(name)}(${code.join(', ')})`, type: f.ret, mat: f.ret === 'mat3' };
    if (this.hooked.has(f.name)) code.push('hooks');
    return { code: `${this.jsName(f)}(${code.join(', ')})`, type: f.ret, mat: f.ret === 'mat3' };
  }

  construct(type, vals, e) {
    if (SCALAR_CTOR[type] && vals.length === 1) {
      const v = vals[0];
      if (v.stat) {
        const conv = { float: (c) => c, int: (c) => `Math.trunc(${c})`, uint: (c) => `(${c} >>> 0)`, bool: (c) => `!!(${c})` }[type];
        return { code: conv(v.code), type, stat: true };
      }
      return { code: `${this.tsl(type)}(${v.code})`, type };
    }
    if (type === 'mat3') {
      if (vals.length === 9) {
        const c = [0, 1, 2].map((k) => `${this.tsl('vec3')}(${vals.slice(3 * k, 3 * k + 3).map((v) => this.node(v, 'float')).join(', ')})`);
        return { code: `[${c.join(', ')}]`, type, mat: true };
      }
      if (vals.length === 3) return { code: `[${vals.map((v) => v.code).join(', ')}]`, type, mat: true };
      if (vals.length === 1 && vals[0].type === 'mat3') return vals[0];
      if (vals.length === 1) return { code: `${this.rt('matDiagonal')}(${this.node(vals[0], 'float')})`, type, mat: true };
      this.fail(`mat3 of ${vals.length} values`, e);
    }
    if (type === 'sampler2D' || type === 'void') this.fail(`a ${type} value`, e);
    const ctor = this.tsl(type);
    const el = base(type);
    return { code: `${ctor}(${vals.map((v) => (v.stat ? this.node(v, el) : v.code)).join(', ')})`, type };
  }

  need(f) {
    this.wanted = this.wanted || new Set();
    this.wanted.add(f);
  }

  // -------------------------------------------------------------- statements
  zero(type) {
    if (type === 'mat3') return `${this.rt('matDiagonal')}(${this.tsl('float')}(0))`;
    if (this.structs.has(type)) this.fail(`an uninitialised ${type}`);
    if (SCALAR_CTOR[type]) return `${this.tsl(type)}(${type === 'bool' ? 'false' : '0'})`;
    return `${this.tsl(type)}(0)`;
  }

  asVar(v, type) {
    if (type === 'mat3') return `${this.rt('matVar')}(${v.code})`;
    if (this.structs.has(type)) return `${this.rt('structVar')}(${v.code})`;
    if (v.stat) return `${this.node(v, type)}.toVar()`;
    return `${this.tsl(type)}(${v.code}).toVar()`;
  }

  block(stmts, scope, out, ctx) {
    for (let k = 0; k < stmts.length; k++) {
      const s = stmts[k];
      if (ctx.early && s.k === 'if' && !s.f && returns(s.t) && k < stmts.length - 1) {
        // if (c) { ... return x; } rest...  ->  if (c) { ... } else { rest }
        this.statement({ ...s, f: { k: 'block', body: stmts.slice(k + 1), line: s.line } }, scope, out, ctx);
        return;
      }
      this.statement(s, scope, out, ctx);
      if (s.k === 'ret') return;
    }
  }

  statement(s, scope, out, ctx) {
    const ind = '  '.repeat(ctx.depth);
    const inner = { ...ctx, depth: ctx.depth + 1 };
    switch (s.k) {
      case 'block': {
        out.push(`${ind}{`);
        this.block(s.body, { vars: new Map(), up: scope }, out, inner);
        out.push(`${ind}}`);
        return;
      }
      case 'decl':
        for (const v of s.vars) {
          const js = this.local(v.name, scope);
          if (v.arr) {
            const n = this.expr(v.arr, scope);
            if (!n.stat) this.fail('an array of a length that is not constant', s);
            if (v.init) this.fail('an array with an initialiser', s);
            out.push(`${ind}const ${js} = Array.from({ length: ${n.code} }, () => ${this.zero(s.type)}.toVar());`);
            scope.vars.set(v.name, { js, type: s.type, arr: true });
            continue;
          }
          const init = v.init ? this.asVar(this.expr(v.init, scope), s.type)
            : s.type === 'mat3' ? `${this.rt('matVar')}(${this.zero('mat3')})` : `${this.zero(s.type)}.toVar()`;
          out.push(`${ind}const ${js} = ${init};`);
          scope.vars.set(v.name, { js, type: s.type });
        }
        return;
      case 'expr': return this.exprStatement(s.e, scope, out, ind);
      case 'if': {
        const c = this.expr(s.c, scope);
        const body = (st) => {
          const lines = [];
          this.statement(st.k === 'block' ? st : { k: 'block', body: [st], line: st.line }, { vars: new Map(), up: scope }, lines, ctx);
          return lines.slice(1, -1);
        };
        if (c.stat) {
          out.push(`${ind}if (${c.code}) {`, ...body(s.t));
          if (s.f) out.push(`${ind}} else {`, ...body(s.f));
          out.push(`${ind}}`);
          return;
        }
        if (c.type !== 'bool') this.fail(`if of a ${c.type}`, s);
        out.push(`${ind}${this.tsl('If')}(${c.code}, () => {`, ...body(s.t));
        if (s.f) out.push(`${ind}}).Else(() => {`, ...body(s.f));
        out.push(`${ind}});`);
        return;
      }
      case 'for': return this.loop(s, scope, out, ctx);
      case 'ret': {
        if (!s.e) { if (ctx.early) return; out.push(`${ind}return;`); return; }
        const v = this.expr(s.e, scope);
        if (ctx.early) {
          if (ctx.ret === 'mat3' || this.structs.has(ctx.ret)) this.fail(`an early return of a ${ctx.ret}`, s);
          out.push(`${ind}${ctx.retVar}.assign(${this.node(v, ctx.ret)});`);
        } else out.push(`${ind}return ${this.structs.has(ctx.ret) || ctx.ret === 'mat3' ? v.code : this.node(v, ctx.ret)};`);
        return;
      }
      case 'break':
        if (!ctx.loop) this.fail('a break outside a loop the emitter keeps as a TSL Loop', s);
        out.push(`${ind}${this.tsl('Break')}();`);
        return;
      default: this.fail(`a ${s.k} statement`, s);
    }
  }

  local(name, scope) {
    for (let s = scope; s; s = s.up) if (s.vars.has(name)) this.fail(`"${name}" hides another variable`);
    return name;
  }

  loop(s, scope, out, ctx) {
    const ind = '  '.repeat(ctx.depth);
    const init = s.init;
    if (init.k !== 'decl' || init.vars.length !== 1 || init.type !== 'int' || !init.vars[0].init) {
      this.fail('a loop not of the form for (int k = a; k < b; ++k)', s);
    }
    const k = init.vars[0].name;
    const from = this.expr(init.vars[0].init, scope);
    const c = s.cond;
    if (c.k !== 'bin' || !['<', '<='].includes(c.op) || c.a.k !== 'id' || c.a.name !== k) this.fail('a loop condition not k < b', s);
    const st = s.step;
    const stepOk = st.k === 'un' && st.op === '++' && st.a.k === 'id' && st.a.name === k;
    if (!stepOk) this.fail('a loop step not ++k', s);
    const to = this.expr(c.b, scope);
    const inner = { vars: new Map(), up: scope };
    const body = s.body.k === 'block' ? s.body.body : [s.body];
    if (from.stat && to.stat && !hasBreak(body)) {
      inner.vars.set(k, { js: k, type: 'int', stat: true });
      out.push(`${ind}for (let ${k} = ${from.code}; ${k} ${c.op} ${to.code}; ${k}++) {`);
      this.block(body, inner, out, { ...ctx, depth: ctx.depth + 1 });
      out.push(`${ind}}`);
      return;
    }
    inner.vars.set(k, { js: k, type: 'int' });
    const index = mentions(body, k) ? `({ i: ${k} })` : '()';
    out.push(`${ind}${this.tsl('Loop')}({ start: ${this.node(from, 'int')}, end: ${this.node(to, 'int')}, type: 'int', condition: '${c.op}' }, ${index} => {`);
    this.block(body, inner, out, { ...ctx, depth: ctx.depth + 1, loop: true });
    out.push(`${ind}});`);
  }

  exprStatement(e, scope, out, ind) {
    if (e.k === 'un' && (e.op === '++' || e.op === '--')) {
      e = { k: 'assign', op: e.op === '++' ? '+=' : '-=', a: e.a, b: { k: 'num', v: '1', type: 'int', line: e.line }, line: e.line };
    }
    if (e.k === 'call') { out.push(`${ind}${this.expr(e, scope).code};`); return; }
    if (e.k !== 'assign') this.fail('a statement that is neither an assignment nor a call', e);
    const a = this.expr(e.a, scope);
    let b = this.expr(e.b, scope);
    if (!a.lv) this.fail('an assignment to something that is not a variable', e);
    if (a.type === 'mat3') {
      if (e.op === '=') out.push(`${ind}${this.rt('matAssign')}(${a.code}, ${b.code});`);
      else if (e.op === '+=' || e.op === '-=') out.push(`${ind}${this.rt('matAssign')}(${a.code}, ${this.rt(e.op === '+=' ? 'matAdd' : 'matSub')}(${a.code}, ${b.code}));`);
      else this.fail(`${e.op} of a matrix`, e);
      return;
    }
    if (this.structs.has(a.type)) this.fail('an assignment of a whole struct (assign its fields)', e);
    if (a.swz) { // a component or a swizzle: the vector is made again, its other components kept
      const vec = a.swz.of;
      const n = size(vec.type);
      const el = base(vec.type);
      const val = `_v${this.tmp++}`;
      const now = e.op === '=' ? this.node(b, a.type) : `${a.code}.${METHOD[e.op[0]]}(${this.node(b, size(a.type) === 1 ? a.type : b.type)})`;
      out.push(`${ind}{`, `${ind}  const ${val} = ${this.tsl(a.type === el ? el : a.type)}(${now}).toVar();`);
      let parts;
      if (a.swz.name) {
        parts = [...'xyzw'.slice(0, n)].map((c) => {
          const at = a.swz.name.indexOf(c);
          return at < 0 ? `${vec.code}.${c}` : a.swz.name.length === 1 ? val : `${val}.${'xyzw'[at]}`;
        });
      } else {
        const i = a.swz.i;
        parts = [...'xyzw'.slice(0, n)].map((c, k) => (i.stat ? `(${i.code} === ${k} ? ${val} : ${vec.code}.${c})`
          : `${this.tsl('select')}(${this.node(i, 'int')}.equal(${this.tsl('int')}(${k})), ${val}, ${vec.code}.${c})`));
      }
      out.push(`${ind}  ${vec.code}.assign(${this.tsl(vec.type)}(${parts.join(', ')}));`, `${ind}}`);
      return;
    }
    if (a.col) { // a matrix column
      out.push(`${ind}${a.code}.${ASSIGN[e.op]}(${this.node(b)});`);
      return;
    }
    if (!ASSIGN[e.op]) this.fail(`${e.op}`, e);
    b = this.node(b, size(a.type) === 1 || size(b.type) > 1 ? a.type : b.type);
    out.push(`${ind}${a.code}.${ASSIGN[e.op]}(${b});`);
  }

  // -------------------------------------------------------------- functions
  func(f) {
    const scope = { vars: new Map(), up: null };
    const out = [];
    const assigned = assignedNames(f.body);
    const pre = [];
    for (const p of f.params) {
      scope.vars.set(p.name, { js: p.name, type: p.type, arr: !!p.arr, stat: false });
      if (p.qual === 'in' && assigned.has(p.name)) { // GLSL passes a copy
        if (p.arr) this.fail(`${f.name}() assigns to its array parameter ${p.name}`, f);
        if (this.structs.has(p.type)) pre.push(`  ${p.name} = ${this.rt('structVar')}(${p.name});`);
        else if (p.type === 'mat3') pre.push(`  ${p.name} = ${this.rt('matVar')}(${p.name});`);
        else pre.push(`  ${p.name} = ${this.tsl(p.type)}(${p.name}).toVar();`);
      }
    }
    const early = hasEarlyReturn(f.body);
    const ctx = { depth: 1, early, ret: f.ret, retVar: '_result' };
    if (early) pre.push(`  const _result = ${this.zero(f.ret)}.toVar();`);
    this.block(f.body, scope, out, ctx);
    if (early) out.push('  return _result;');
    const doc = f.doc.length ? `/** glsl: ${f.name}.\n${f.doc.map((l) => ` * ${l}`).join('\n')} */\n` : `/** glsl: ${f.name}. */\n`;
    const params = [...f.params.map((p) => p.name), ...(this.hooked.has(f.name) ? ['hooks'] : [])].join(', ');
    return `${doc}export function ${this.jsName(f)}(${params}) {\n${[...pre, ...out].join('\n')}\n}\n`;
  }
}

function returns(s) {
  if (s.k === 'ret') return true;
  if (s.k === 'block') return s.body.length > 0 && returns(s.body[s.body.length - 1]);
  if (s.k === 'if') return !!s.f && returns(s.t) && returns(s.f);
  return false;
}

function hasBreak(stmts) {
  return stmts.some((s) => s.k === 'break' || (s.k === 'block' && hasBreak(s.body))
    || (s.k === 'if' && (hasBreak([s.t]) || (s.f && hasBreak([s.f])))));
}

function hasEarlyReturn(body) {
  const walk = (s, last) => {
    if (s.k === 'ret') return !last;
    if (s.k === 'block') return s.body.some((x, k) => walk(x, last && k === s.body.length - 1));
    if (s.k === 'if') return walk(s.t, false) || (s.f && walk(s.f, false));
    if (s.k === 'for') return walk(s.body, false);
    return false;
  };
  return body.some((s, k) => walk(s, k === body.length - 1));
}

/** Whether the statements read or write identifier `name`. */
function mentions(body, name) {
  const walk = (e) => {
    if (!e || typeof e !== 'object') return false;
    if (Array.isArray(e)) return e.some(walk);
    if (e.k === 'id' && e.name === name) return true;
    return Object.values(e).some((v) => v && typeof v === 'object' && walk(v));
  };
  return walk(body);
}

function calledNames(body) {
  const names = new Set();
  const walk = (e) => {
    if (!e || typeof e !== 'object') return;
    if (Array.isArray(e)) { e.forEach(walk); return; }
    if (e.k === 'call') names.add(e.name);
    Object.values(e).forEach((v) => { if (v && typeof v === 'object') walk(v); });
  };
  walk(body);
  return names;
}

function assignedNames(body) {
  const names = new Set();
  const root = (e) => (e.k === 'id' ? e.name : e.k === 'field' || e.k === 'index' ? root(e.a) : null);
  const expr = (e) => {
    if (!e || typeof e !== 'object') return;
    if (e.k === 'assign') names.add(root(e.a));
    if (e.k === 'un' && (e.op === '++' || e.op === '--')) names.add(root(e.a));
    for (const v of Object.values(e)) {
      if (Array.isArray(v)) v.forEach(expr);
      else if (v && typeof v === 'object' && v.k) expr(v);
    }
  };
  body.forEach(expr);
  return names;
}

/**
 * TSL node functions from GLSL sources.
 * @param {{name: string, text: string}[]} sources the files, in include order
 * @param {object} options {defines: {NAME: value}, only: [GLSL function names to emit (and what they call)],
 *   header: the file's first comment lines, runtime: the module the helpers come from, emitted: a Set this fills
 *   with the JavaScript names of the functions emitted (an overload's with its parameter types), external: [{module, names}, ...] -- functions other emitted
 *   modules hold (their `emitted`), imported from them instead of emitted again, switches: [define names] kept as
 *   static ifs of the runtime's `switches`}
 * @returns {string} the JavaScript module
 */
export function emitTsl(sources, { defines = {}, only = null, header = [], runtime = './tsl_runtime.js', imports = [],
  emitted = null, external = [], switches = [] } = {}) {
  const items = [];
  let structs = new Map();
  for (const { name, text } of sources) {
    const parser = new Parser(tokenize(preprocess(text, defines, name, switches), name), name);
    parser.structs = structs;
    const got = parser.program();
    got.forEach((x) => { x.where = name; });
    items.push(...got);
    structs = parser.structs;
  }
  const em = new Emitter(items, sources.map((s) => s.name).join('+'));
  // a switch: a define the program chooses when it builds its nodes, read from the runtime's `switches`
  for (const name of switches) em.consts.set(name, { js: `switches.${name}`, type: 'bool', stat: true, switch: true });
  for (const c of items.filter((x) => x.kind === 'const')) {
    const v = em.expr(c.value, { vars: new Map(), up: null });
    if (!v.stat) em.fail(`const ${c.name} is not a number`, c);
    em.consts.set(c.name, { js: c.name, type: c.type, stat: true, value: v.code });
  }
  // what to emit: the named functions and every function they call
  const funcs = items.filter((x) => x.kind === 'func');
  let want = new Set(only ? funcs.filter((f) => only.includes(f.name)) : funcs);
  if (only) for (const n of only) if (!funcs.some((f) => f.name === n)) throw new GlslError(`no function ${n} in the sources`);
  const bodies = new Map();
  const outside = new Map(); // module -> the JavaScript names taken from it
  for (;;) {
    for (const f of want) {
      if (bodies.has(f)) continue;
      const holder = external.find((x) => x.names.has(em.jsName(f))); // an overload by its own name
      if (holder) { // another module holds it
        if (!outside.has(holder.module)) outside.set(holder.module, new Set());
        outside.get(holder.module).add(em.jsName(f));
        bodies.set(f, null);
        continue;
      }
      em.where = f.where;
      bodies.set(f, em.func(f));
    }
    const more = [...(em.wanted || [])].filter((f) => !bodies.has(f));
    if (!more.length) break;
    want = new Set([...want, ...more]);
  }
  const tsl = [...em.used].sort();
  const rt = [...(em.runtime || [])].sort();
  const own = [...bodies.values()].filter((b) => b !== null);
  const consts = [...em.consts.values()].filter((c) => !c.switch && own.some((b) => new RegExp(`\\b${c.js}\\b`).test(b)));
  if (switches.length && own.some((b) => /\bswitches\./.test(b))) rt.push('switches');
  rt.sort();
  if (emitted) for (const [f, b] of bodies) if (b !== null) emitted.add(em.jsName(f));
  return [
    ...header.map((l) => `// ${l}`.trimEnd()),
    '',
    `import { ${tsl.join(', ')} } from 'three/tsl';`,
    ...(rt.length ? [`import { ${rt.join(', ')} } from '${runtime}';`] : []),
    ...[...outside].map(([module, names]) => `import { ${[...names].sort().join(', ')} } from '${module}';`),
    ...imports,
    '',
    ...consts.map((c) => `export const ${c.js} = ${c.value};`),
    ...(consts.length ? [''] : []),
    funcs.filter((f) => bodies.get(f)).map((f) => bodies.get(f)).join('\n'),
  ].join('\n');
}

/**
 * The fields of struct `name` in a GLSL text: [[field, type], ...] in their order.
 * @param {string} text the GLSL source
 * @param {string} name the struct
 * @param {string} where the file (for errors)
 */
export function structFields(text, name, where = name) {
  const parser = new Parser(tokenize(preprocess(text, {}, where), where), where);
  const items = parser.program();
  const s = items.find((x) => x.kind === 'struct' && x.name === name);
  if (!s) throw new GlslError(`${where}: no struct ${name}`);
  return s.fields.map((f) => [f.name, f.type]);
}

export { GlslError };
