// Field readers of a frame payload, included inside a module body whose payload input is named
// `pay` (byte i in pay[8*i+:8]): pb(i) is byte i, be32(i) the big-endian 32-bit field at byte i.
// They read `pay` directly, so a simulator need not copy the whole payload for every field.
function [7:0] pb;
  input integer i;
  begin
    pb = pay[8*i+:8];
  end
endfunction

function [31:0] be32;
  input integer i;
  begin
    be32 = {pay[8*i+:8], pay[8*(i+1)+:8], pay[8*(i+2)+:8], pay[8*(i+3)+:8]};
  end
endfunction
