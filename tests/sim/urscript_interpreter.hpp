#pragma once
// A test's interpreter for the subset of URScript that sim::urscript_program writes, with URScript's
// 32-bit floats and ints: one `def NAME(): ... end` block (comments outside it), assignments, while /
// if / elif / else ... end, halt, + - * / and comparisons, unary minus, lists and indexing a list by
// an int, and the calls sin, cos, textmsg, popup, get_actual_joint_positions, set_payload, set_target_payload, movej,
// servoj, stopj (named arguments as URScript takes them). What the program commands is recorded, so
// a test can compare it with the motion it was written from; the arm's pose that
// get_actual_joint_positions returns is the test's (Interpreter::arm_at).
// Anything outside the subset (an unknown name, a call, a statement, int / int) is an error: the
// test then fails on a program that the controller might read otherwise.
#include <cctype>
#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace urscript_test {

struct Value {
  enum Kind { Int, Float, Bool, Str, List } kind = Int;
  long i = 0;
  float f = 0.0f;
  bool b = false;
  std::string s;
  std::vector<Value> list;
  static Value of_int(long v) { Value x; x.kind = Int; x.i = v; return x; }
  static Value of_float(float v) { Value x; x.kind = Float; x.f = v; return x; }
  static Value of_bool(bool v) { Value x; x.kind = Bool; x.b = v; return x; }
  bool numeric() const { return kind == Int || kind == Float; }
  float as_float() const {
    if (!numeric()) throw std::runtime_error("a number was expected");
    return kind == Int ? static_cast<float>(i) : f;
  }
};

struct Call {
  std::string name;
  std::vector<Value> args;
  std::map<std::string, Value> named;
};

// what the program did, in order
struct Trace {
  std::vector<Call> calls;        // every builtin call but sin/cos
  std::vector<std::vector<float>> servo_targets;
  long statements = 0;
  bool halted = false;  // the program ran `halt`
};

class Interpreter {
 public:
  explicit Interpreter(const std::string& text) { parse(text); }
  Trace run(long max_statements = 200'000'000) {
    Trace t;
    vars_.clear();
    limit_ = max_statements;
    try {
      exec(body_, t);
    } catch (const Halt&) {
      t.halted = true;
    }
    return t;
  }
  /// The pose get_actual_joint_positions() returns [rad]; without it the call is an error.
  void arm_at(std::vector<float> q) { arm_ = std::move(q); }
  const std::string& name() const { return name_; }
  /// whether the file calls its def after it
  bool called() const { return called_; }

 private:
  struct Expr {
    enum Kind { Num, Name, Str, ListLit, Unary, Binary, CallE, Index } kind;
    Value value;
    std::string text;  // name, operator, function
    std::vector<std::unique_ptr<Expr>> args;
    std::vector<std::string> arg_names;  // "" for a positional argument
  };
  struct Halt {};
  struct Stmt {
    enum Kind { Assign, CallS, While, If, HaltS } kind;
    std::string target;
    std::unique_ptr<Expr> expr;
    std::vector<std::pair<std::unique_ptr<Expr>, std::vector<Stmt>>> branches;  // if/elif (condition), else (null)
    std::vector<Stmt> body;  // while
    int line = 0;
  };

  // ---- lexing one line
  struct Lexer {
    std::string s;
    size_t p = 0;
    int line;
    void skip() {
      while (p < s.size() && (s[p] == ' ')) ++p;
    }
    [[noreturn]] void fail(const std::string& what) const {
      throw std::runtime_error("line " + std::to_string(line) + ": " + what + " at '" + s.substr(p) + "'");
    }
    bool eat(const std::string& t) {
      skip();
      if (s.compare(p, t.size(), t) == 0) {
        p += t.size();
        return true;
      }
      return false;
    }
    bool at_end() {
      skip();
      return p >= s.size();
    }
    std::string ident() {
      skip();
      size_t q = p;
      if (q < s.size() && (std::isalpha(static_cast<unsigned char>(s[q])) || s[q] == '_'))
        while (q < s.size() && (std::isalnum(static_cast<unsigned char>(s[q])) || s[q] == '_')) ++q;
      std::string id = s.substr(p, q - p);
      p = q;
      return id;
    }
  };

  std::unique_ptr<Expr> primary(Lexer& L) {
    L.skip();
    auto e = std::make_unique<Expr>();
    if (L.eat("(")) {
      e = expression(L);
      if (!L.eat(")")) L.fail("')' expected");
      return e;
    }
    if (L.eat("[")) {
      e->kind = Expr::ListLit;
      if (!L.eat("]")) {
        do e->args.push_back(expression(L));
        while (L.eat(","));
        if (!L.eat("]")) L.fail("']' expected");
      }
      return e;
    }
    if (L.eat("\"")) {
      const size_t q = L.s.find('"', L.p);
      if (q == std::string::npos) L.fail("unclosed string");
      e->kind = Expr::Str;
      e->value.kind = Value::Str;
      e->value.s = L.s.substr(L.p, q - L.p);
      L.p = q + 1;
      return e;
    }
    if (L.p < L.s.size() && std::isdigit(static_cast<unsigned char>(L.s[L.p]))) {
      size_t q = L.p;
      bool dot = false;
      while (q < L.s.size() && (std::isdigit(static_cast<unsigned char>(L.s[q])) || L.s[q] == '.')) dot |= L.s[q++] == '.';
      if (q < L.s.size() && (L.s[q] == 'e' || L.s[q] == 'E')) L.fail("a number in exponent notation");
      const std::string num = L.s.substr(L.p, q - L.p);
      L.p = q;
      e->kind = Expr::Num;
      e->value = dot ? Value::of_float(static_cast<float>(std::stod(num))) : Value::of_int(std::stol(num));
      return e;
    }
    const std::string id = L.ident();
    if (id.empty()) L.fail("an expression expected");
    if (L.eat("(")) {
      e->kind = Expr::CallE;
      e->text = id;
      if (!L.eat(")")) {
        do {
          L.skip();
          const size_t save = L.p;
          std::string nm = L.ident();
          if (!nm.empty() && L.eat("=") && !L.eat("=")) {
            e->arg_names.push_back(nm);
          } else {
            L.p = save;
            e->arg_names.push_back("");
          }
          e->args.push_back(expression(L));
        } while (L.eat(","));
        if (!L.eat(")")) L.fail("')' expected");
      }
      return e;
    }
    if (id == "True" || id == "False") {
      e->kind = Expr::Num;
      e->value = Value::of_bool(id == "True");
      return e;
    }
    e->kind = Expr::Name;
    e->text = id;
    if (L.eat("[")) {  // a list's element
      auto ix = std::make_unique<Expr>();
      ix->kind = Expr::Index;
      ix->args.push_back(std::move(e));
      ix->args.push_back(expression(L));
      if (!L.eat("]")) L.fail("']' expected");
      return ix;
    }
    return e;
  }
  std::unique_ptr<Expr> unary(Lexer& L) {
    if (L.eat("-")) {
      auto e = std::make_unique<Expr>();
      e->kind = Expr::Unary;
      e->text = "-";
      e->args.push_back(unary(L));
      return e;
    }
    return primary(L);
  }
  std::unique_ptr<Expr> binary(Lexer& L, int level) {
    static const std::vector<std::vector<std::string>> ops{{"<=", ">=", "==", "!=", "<", ">"}, {"+", "-"}, {"*", "/"}};
    if (level == 3) return unary(L);
    auto lhs = binary(L, level + 1);
    for (;;) {
      std::string op;
      for (const std::string& o : ops[level])
        if (L.eat(o)) {
          op = o;
          break;
        }
      if (op.empty()) return lhs;
      auto e = std::make_unique<Expr>();
      e->kind = Expr::Binary;
      e->text = op;
      e->args.push_back(std::move(lhs));
      e->args.push_back(binary(L, level + 1));
      lhs = std::move(e);
      if (level == 0) return lhs;  // (comparisons do not chain)
    }
  }
  std::unique_ptr<Expr> expression(Lexer& L) { return binary(L, 0); }

  // ---- statements
  void parse(const std::string& text) {
    std::vector<std::pair<int, std::string>> lines;
    size_t p = 0;
    int no = 0;
    while (p <= text.size()) {
      const size_t q = text.find('\n', p);
      std::string l = text.substr(p, q == std::string::npos ? std::string::npos : q - p);
      ++no;
      if (l.find('\t') != std::string::npos) throw std::runtime_error("line " + std::to_string(no) + ": a tab");
      const size_t first = l.find_first_not_of(' ');
      if (first != std::string::npos && l[first] != '#') lines.emplace_back(no, l.substr(first));
      if (q == std::string::npos) break;
      p = q + 1;
    }
    if (lines.empty()) throw std::runtime_error("no statement");
    Lexer L{lines[0].second, 0, lines[0].first};
    if (!L.eat("def ")) throw std::runtime_error("the program does not start with 'def'");
    name_ = L.ident();
    if (name_.empty() || !L.eat("():") || !L.at_end()) L.fail("'def NAME():' expected");
    size_t k = 1;
    std::string closer;
    body_ = block(lines, k, closer);
    if (closer != "end") throw std::runtime_error("the def is not closed by 'end'");
    // one call of the def after it (a Script node's file), nothing else
    if (k < lines.size() && lines[k].second == name_ + "()") {
      called_ = true;
      ++k;
    }
    if (k != lines.size()) throw std::runtime_error("line " + std::to_string(lines[k].first) + ": a statement after the def's end");
  }
  // statements up to the line that closes the block (end, elif, else), which `closer` gets
  std::vector<Stmt> block(const std::vector<std::pair<int, std::string>>& lines, size_t& k, std::string& closer) {
    std::vector<Stmt> out;
    while (k < lines.size()) {
      const auto& [no, text] = lines[k++];
      Lexer L{text, 0, no};
      if (text == "end" || text == "else:" || text.rfind("elif ", 0) == 0) {
        closer = text;
        return out;
      }
      Stmt st;
      st.line = no;
      if (text == "halt") {
        st.kind = Stmt::HaltS;
      } else if (L.eat("while ")) {
        st.kind = Stmt::While;
        st.expr = expression(L);
        if (!L.eat(":") || !L.at_end()) L.fail("':' expected");
        std::string c;
        st.body = block(lines, k, c);
        if (c != "end") L.fail("'while' not closed by 'end'");
      } else if (L.eat("if ")) {
        st.kind = Stmt::If;
        auto cond = expression(L);
        if (!L.eat(":") || !L.at_end()) L.fail("':' expected");
        for (;;) {
          std::string c;
          auto body = block(lines, k, c);
          st.branches.emplace_back(std::move(cond), std::move(body));
          if (c.empty()) L.fail("'if' not closed by 'end'");
          if (c == "end") break;
          if (c == "else:") {
            std::string c2;
            auto last = block(lines, k, c2);
            if (c2 != "end") L.fail("'else' not closed by 'end'");
            st.branches.emplace_back(nullptr, std::move(last));
            break;
          }
          Lexer E{c, 5, no};  // elif
          cond = expression(E);
          if (!E.eat(":") || !E.at_end()) E.fail("':' expected");
        }
      } else {
        const size_t save = L.p;
        const std::string id = L.ident();
        if (!id.empty() && L.eat("=") && !L.eat("=")) {
          st.kind = Stmt::Assign;
          st.target = id;
          st.expr = expression(L);
        } else {
          L.p = save;
          st.kind = Stmt::CallS;
          st.expr = expression(L);
          if (st.expr->kind != Expr::CallE) L.fail("a statement expected");
        }
        if (!L.at_end()) L.fail("end of line expected");
      }
      out.push_back(std::move(st));
    }
    closer.clear();
    return out;
  }

  // ---- evaluation
  Value eval(const Expr& e, Trace& t) {
    switch (e.kind) {
      case Expr::Num:
      case Expr::Str: return e.value;
      case Expr::Name: {
        const auto it = vars_.find(e.text);
        if (it == vars_.end()) throw std::runtime_error("unknown variable '" + e.text + "'");
        return it->second;
      }
      case Expr::ListLit: {
        Value v;
        v.kind = Value::List;
        for (const auto& a : e.args) v.list.push_back(eval(*a, t));
        return v;
      }
      case Expr::Index: {
        const Value l = eval(*e.args[0], t), i = eval(*e.args[1], t);
        if (l.kind != Value::List) throw std::runtime_error("'" + e.args[0]->text + "' indexed, but it is no list");
        if (i.kind != Value::Int) throw std::runtime_error("a list indexed by a value that is no int");
        if (i.i < 0 || i.i >= static_cast<long>(l.list.size())) throw std::runtime_error("a list index out of range");
        return l.list[static_cast<size_t>(i.i)];
      }
      case Expr::Unary: {
        const Value a = eval(*e.args[0], t);
        if (a.kind == Value::Int) return Value::of_int(-a.i);
        return Value::of_float(-a.as_float());
      }
      case Expr::Binary: {
        const Value a = eval(*e.args[0], t), b = eval(*e.args[1], t);
        const std::string& op = e.text;
        if (!a.numeric() || !b.numeric()) throw std::runtime_error("'" + op + "' of a value that is no number");
        const bool ints = a.kind == Value::Int && b.kind == Value::Int;
        if (op == "/" && ints) throw std::runtime_error("int / int (the controller may divide as integers)");
        if (op == "<" || op == ">" || op == "<=" || op == ">=" || op == "==" || op == "!=") {
          const double x = ints ? static_cast<double>(a.i) : a.as_float(), y = ints ? static_cast<double>(b.i) : b.as_float();
          return Value::of_bool(op == "<" ? x < y : op == ">" ? x > y : op == "<=" ? x <= y : op == ">=" ? x >= y : op == "==" ? x == y : x != y);
        }
        if (ints) return Value::of_int(op == "+" ? a.i + b.i : op == "-" ? a.i - b.i : a.i * b.i);
        const float x = a.as_float(), y = b.as_float();  // 32-bit arithmetic, each result rounded
        return Value::of_float(op == "+" ? x + y : op == "-" ? x - y : op == "*" ? x * y : x / y);
      }
      case Expr::CallE: {
        Call c;
        c.name = e.text;
        for (size_t k = 0; k < e.args.size(); ++k) {
          Value v = eval(*e.args[k], t);
          if (e.arg_names[k].empty()) c.args.push_back(v);
          else c.named[e.arg_names[k]] = v;
        }
        if (c.name == "sin" || c.name == "cos") {
          if (c.args.size() != 1 || !c.named.empty()) throw std::runtime_error(c.name + " takes one argument");
          const double x = c.args[0].as_float();
          return Value::of_float(static_cast<float>(c.name == "sin" ? std::sin(x) : std::cos(x)));
        }
        if (c.name == "get_actual_joint_positions") {
          if (!c.args.empty() || !c.named.empty()) throw std::runtime_error(c.name + " takes no argument");
          if (arm_.size() != 6) throw std::runtime_error("the test gave the arm no pose of six joints (arm_at)");
          Value v;
          v.kind = Value::List;
          for (float x : arm_) v.list.push_back(Value::of_float(x));
          t.calls.push_back(std::move(c));
          return v;
        }
        static const std::map<std::string, std::vector<std::string>> known{
            {"textmsg", {}}, {"set_payload", {}}, {"set_target_payload", {}}, {"movej", {"a", "v"}}, {"servoj", {"t", "lookahead_time", "gain"}}, {"stopj", {}},
            {"popup", {"title", "warning", "error", "blocking"}}};
        const auto it = known.find(c.name);
        if (it == known.end()) throw std::runtime_error("unknown function '" + c.name + "'");
        for (const auto& [nm, v] : c.named) {
          bool ok = false;
          for (const std::string& k : it->second) ok |= k == nm;
          if (!ok) throw std::runtime_error(c.name + " has no argument '" + nm + "'");
        }
        // positional arguments as the subset uses them: textmsg(s), set_payload(m, [cx, cy, cz]),
        // movej(q, a=, v=), servoj(q, t=, lookahead_time=, gain=), stopj(a)
        // textmsg(s1, s2=""), popup(s, title=, warning=, error=, blocking=)
        const size_t positional = c.name == "set_payload" ? 2 : c.name == "set_target_payload" ? 3 : 1;
        if (c.args.size() != positional && !(c.name == "textmsg" && c.args.size() == 2))
          throw std::runtime_error(c.name + " takes " + std::to_string(positional) + " positional argument(s)");
        if ((c.name == "textmsg" || c.name == "popup") && c.args[0].kind != Value::Str)
          throw std::runtime_error(c.name + "'s first argument is a string");
        for (const auto& [nm, v] : c.named)
          if (c.name == "popup" && (nm == "title" ? v.kind != Value::Str : v.kind != Value::Bool))
            throw std::runtime_error("popup's " + nm + " is a " + (nm == "title" ? "string" : "bool"));
        const bool joints = c.name == "movej" || c.name == "servoj";
        if (joints && (c.args[0].kind != Value::List || c.args[0].list.size() != 6))
          throw std::runtime_error(c.name + " takes a list of six joint positions");
        if ((c.name == "set_payload" || c.name == "set_target_payload") && (c.args[1].kind != Value::List || c.args[1].list.size() != 3))
          throw std::runtime_error(c.name + " takes a centre of gravity of three numbers");
        if (c.name == "set_target_payload" && (c.args[2].kind != Value::List || c.args[2].list.size() != 6))
          throw std::runtime_error("set_target_payload takes an inertia of six numbers [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]");
        if (c.name == "servoj") {
          std::vector<float> q;
          for (const Value& v : c.args[0].list) q.push_back(v.as_float());
          t.servo_targets.push_back(q);
        }
        t.calls.push_back(std::move(c));
        return Value{};
      }
    }
    return Value{};
  }
  bool truth(const Value& v) {
    if (v.kind != Value::Bool) throw std::runtime_error("a condition that is not a comparison");
    return v.b;
  }
  void exec(const std::vector<Stmt>& stmts, Trace& t) {
    for (const Stmt& s : stmts) {
      if (++t.statements > limit_) throw std::runtime_error("the program runs on past the statement limit");
      switch (s.kind) {
        case Stmt::Assign: {
          Value v = eval(*s.expr, t);
          const auto it = vars_.find(s.target);
          if (it != vars_.end() && it->second.kind != v.kind)
            throw std::runtime_error("line " + std::to_string(s.line) + ": '" + s.target + "' changes type");
          vars_[s.target] = v;
          break;
        }
        case Stmt::CallS: eval(*s.expr, t); break;
        case Stmt::HaltS: throw Halt{};
        case Stmt::While:
          while (truth(eval(*s.expr, t))) exec(s.body, t);
          break;
        case Stmt::If:
          for (const auto& [cond, body] : s.branches)
            if (!cond || truth(eval(*cond, t))) {
              exec(body, t);
              break;
            }
          break;
      }
    }
  }

  std::string name_;
  std::vector<Stmt> body_;
  std::map<std::string, Value> vars_;
  long limit_ = 0;
  bool called_ = false;
  std::vector<float> arm_;
};

}  // namespace urscript_test
