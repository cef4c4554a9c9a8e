// MATLAB's .fis format (versions 1 and 2) and GNU Octave fuzzy-logic-toolkit's variant of it.
// Interval type-2 files (Type='mamdanitype2' / 'sugenotype2') append MATLAB's LowerScale and LowerLag to an MF
// line: MF1='low':'trimf',[0 1 2],0.9,[0.1 0.1] (docs/matlab_fis.md says what could not be confirmed).
// The format is line oriented: section headers, `Key = value` lines, MF lines and, under [Rules], rule lines.
// The grammar only recognises the shape of each line; compiler/frontend/matlab_fis_reader.cpp checks which keys
// belong where, counts, indices and values (docs/matlab_fis.md lists every rule).
grammar MatlabFis;

file : NEWLINE* (line (NEWLINE+ line)*)? NEWLINE* EOF ;

line
  : SECTION                                                                # sectionLine
  | key=IDENT '=' name=STRING ':' kind=STRING ',' params=vector
      (',' lowerScale=value (',' lowerLag=value)?)?                        # mfLine
  | key=IDENT '=' value                                                    # keyLine
  | antecedent=indexList ',' consequent=indexList
      '(' weight=signedNumber ')' ':' connective=signedNumber              # ruleLine
  ;

value
  : STRING                                                                 # stringValue
  | vector                                                                 # vectorValue
  | expression                                                             # numberValue
  ;

// MATLAB's readfis evaluates values with eval(), so `[-pi/4 pi/4]` is a valid range. Inside brackets a space
// separates elements, which is why `+` and `-` are binary only inside parentheses (see `sum`).
vector : '[' (expression (','? expression)*)? ']' ;

expression : unary (op=('*' | '/') unary)* ;
unary
  : sign=('-' | '+') unary                                                 # signedUnary
  | atom ('^' exponent=unary)?                                             # powerUnary
  ;
atom
  : NUMBER                                                                 # numberAtom
  | IDENT                                                                  # nameAtom
  | '(' sum ')'                                                            # groupAtom
  ;
sum : expression (op=('+' | '-') expression)* ;

// Rule entries: MF index, negative for NOT, fractional part for Octave's hedges (.05 .2 .3 .4).
indexList : signedNumber+ ;
signedNumber : sign=('-' | '+')? NUMBER ;

SECTION : '[' ('System' | 'Input' [0-9]+ | 'Output' [0-9]+ | 'Rules') ']' ;
// MATLAB strings: a quote inside is doubled.
STRING : '\'' (~['\r\n] | '\'\'')* '\'' ;
NUMBER : DIGITS ('.' DIGITS?)? EXPONENT? | '.' DIGITS EXPONENT? ;
IDENT : [A-Za-z_] [A-Za-z_0-9]* ;

EQUALS : '=' ;
COLON : ':' ;
COMMA : ',' ;
LPAREN : '(' ;
RPAREN : ')' ;
LBRACKET : '[' ;
RBRACKET : ']' ;
PLUS : '+' ;
MINUS : '-' ;
STAR : '*' ;
SLASH : '/' ;
CARET : '^' ;

// MATLAB comments start with %, Octave's also with #; both may follow leading blanks.
COMMENT : ('%' | '#') ~[\r\n]* -> skip ;
WS : [ \t\f]+ -> skip ;
NEWLINE : '\r'? '\n' | '\r' ;

// Never a lexer error: these reach the parser, whose error names the line and column (see the reader).
UNTERMINATED_STRING : '\'' ~['\r\n]* ;
UNEXPECTED_CHARACTER : . ;

fragment DIGITS : [0-9]+ ;
fragment EXPONENT : [eE] [+-]? DIGITS ;
